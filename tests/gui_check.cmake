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
elseif(MODE STREQUAL "inspect")
  # The guide inspector opened on a pixel as a Ctrl+click would: its chart's variance factors.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --strategy full --set camera.resolution=[160,90] --inspect 95,40
              --screenshot ${OUT}/inspect.png --after-spp 2 --quit)
  if(NOT LAST_OUTPUT MATCHES "inspector: pixel \\(95, 40\\), full, camera ray: .*guided [0-9.]+, tracked [0-9.]+, mis [0-9.]+")
    message(FATAL_ERROR "no inspection reported")
  endif()
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
elseif(MODE STREQUAL "input")
  # Real input events (xdotool): a left drag on the image tumbles the camera, a drag that starts on
  # the Parameters panel does not (ImGui wants that mouse), and F frames the volume. The screenshot's
  # settings metadata says where the camera ended up.
  file(WRITE ${OUT}/drive.sh
       "${VIEWER} ${SCENE} --set camera.resolution=[160,90] --screenshot ${OUT}/$1.png --after 3 --quit &
        sleep 2.5
        if [ $1 = image ]; then xdotool mousemove 400 400 sleep 0.2 mousedown 1 sleep 0.2 mousemove 450 410 sleep 0.2 mousemove 520 420 sleep 0.2 mouseup 1; fi
        if [ $1 = panel ]; then xdotool mousemove 1300 600 sleep 0.2 mousedown 1 sleep 0.2 mousemove 1350 610 sleep 0.2 mousemove 1420 620 sleep 0.2 mouseup 1; fi
        if [ $1 = frame ]; then xdotool mousemove 400 400 sleep 0.2 key f; fi
        wait $!
")
  foreach(case image panel frame)
    run_checked(${XVFB} sh ${OUT}/drive.sh ${case})
    execute_process(COMMAND ${COMPARE} --metadata ${OUT}/${case}.png settings OUTPUT_VARIABLE settings RESULT_VARIABLE rc)
    if(NOT rc EQUAL 0)
      message(FATAL_ERROR "no settings metadata in ${OUT}/${case}.png")
    endif()
    string(JSON position_${case} GET "${settings}" camera position)
    string(JSON look_at_${case} GET "${settings}" camera look_at)
    message("${case}: camera position ${position_${case}}, look_at ${look_at_${case}}")
  endforeach()
  file(READ ${SCENE} scene_text)
  string(JSON file_position GET "${scene_text}" camera position)
  string(JSON file_x GET "${file_position}" 0)
  string(JSON image_x GET "${position_image}" 0)
  string(JSON panel_x GET "${position_panel}" 0)
  if(image_x EQUAL file_x)
    message(FATAL_ERROR "a drag on the image did not move the camera")
  endif()
  if(NOT panel_x EQUAL file_x)
    message(FATAL_ERROR "a drag on the panel moved the camera (${panel_x} vs ${file_x})")
  endif()
  if("${look_at_frame}" STREQUAL "${look_at_panel}")
    message(FATAL_ERROR "F did not frame the volume (look_at unchanged)")
  endif()
elseif(MODE STREQUAL "figure")
  # The talk's Fig. 1 as a scripted comparison: three panes at equal time, a rendered reference.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --panes conventional,emission,full --equal-time 2
              --reference-spp 64 --figure ${OUT}/figure.png --quit)
  run_checked(${COMPARE} --figure ${OUT}/figure.png ${OUT}/figure.csv 3)
  foreach(pane conventional emission full)
    if(NOT EXISTS ${OUT}/figure-${pane}.exr)
      message(FATAL_ERROR "missing ${OUT}/figure-${pane}.exr")
    endif()
  endforeach()
endif()
