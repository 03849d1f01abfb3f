# GUI tests under Xvfb, run as a user would: candela starts on a scene, is driven by its scriptable
# options, takes a screenshot and quits. Arguments: CLI, VIEWER, XVFB_RUN, COMPARE, SCENE, OUT, MODE.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
set(XVFB ${XVFB_RUN} -a -s "-screen 0 1500x820x24")
set(ENV{ASAN_OPTIONS} detect_leaks=0)  # Mesa leaks a few bytes at exit

function(run_checked)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 240)
  message("${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}")
  endif()
  set(LAST_OUTPUT "${out}${err}" PARENT_SCOPE)
endfunction()

if(MODE STREQUAL "screenshot")
  # The viewer's screenshot against the CLI's render of the same scene, strategy, seed and spp.
  run_checked(${CLI} render ${SCENE} --strategy emission --spp 8 --set camera.resolution=[320,180] -o ${OUT}/cli.exr)
  run_checked(${XVFB} ${VIEWER} ${SCENE} --strategy emission --set camera.resolution=[320,180]
              --screenshot ${OUT}/gui.png --after-spp 8 --quit)
  run_checked(${COMPARE} ${OUT}/gui.png ${OUT}/gui.exr ${OUT}/cli.exr 8)
elseif(MODE STREQUAL "bad_input")
  # A bad OCIO config and an absurd edit typed into a field: visible messages, the last good scene
  # keeps rendering, the screenshot is still taken and the app exits cleanly.
  file(WRITE ${OUT}/broken.ocio "ocio_profile_version: 2\nroles: [broken\n")
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --ocio ${OUT}/broken.ocio
              --edit volumes.0.g=7 --edit volumes.0.sigma_t_scale=-3 --edit volumes.0.file=missing.vdb --edit strategy.preset=bogus
              --screenshot ${OUT}/after-bad-edits.png --after-spp 4 --quit)
  foreach(expected "broken.ocio" "using the shipped config" "volumes.0.g" "volumes.0.sigma_t_scale" "exactly one of"
          "strategy.preset" "screenshot: wrote")
    string(FIND "${LAST_OUTPUT}" "${expected}" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "expected the viewer to report \"${expected}\"")
    endif()
  endforeach()
  # A scene that cannot load at all: a clear message and a non-zero exit, no hang.
  file(WRITE ${OUT}/broken.json "{ \"camera\": { \"position\": [0, 0, 1] }")
  execute_process(COMMAND ${XVFB} ${VIEWER} ${OUT}/broken.json --quit RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
  message("${out}${err}")
  if(rc EQUAL 0)
    message(FATAL_ERROR "a broken scene with --quit should exit non-zero")
  endif()
  string(FIND "${err}" "broken.json" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "expected the error to name broken.json")
  endif()
elseif(MODE STREQUAL "reload")
  # The scene file changes on disk while the viewer renders it: first to a scene whose VDB is missing
  # (a message; the last good scene keeps rendering), then back to a good one (reloaded and shown).
  file(READ ${SCENE} text)
  file(WRITE ${OUT}/scene.json "${text}")
  string(REGEX REPLACE "\"generator\": {\"type\": \"torch\"[^}]*}" "\"file\": \"missing.vdb\", \"temperature_grid\": \"temperature\"" broken "${text}")
  file(WRITE ${OUT}/broken.json "${broken}")
  # (A script file: CMake would split a command string at its semicolons.)
  file(WRITE ${OUT}/edit-while-running.sh
       "${XVFB_RUN} -a -s '-screen 0 1500x820x24' ${VIEWER} ${OUT}/scene.json --set camera.resolution=[160,90] \\
          --screenshot ${OUT}/reloaded.png --after 4 --quit &
        sleep 2.5
        cp ${OUT}/broken.json ${OUT}/scene.json
        sleep 1.5
        cp ${SCENE} ${OUT}/scene.json
        wait $!
")
  run_checked(sh ${OUT}/edit-while-running.sh)
  foreach(expected "the file changed" "missing.vdb" "still showing the last good scene" "screenshot: wrote")
    string(FIND "${LAST_OUTPUT}" "${expected}" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "expected the viewer to report \"${expected}\"")
    endif()
  endforeach()
endif()
