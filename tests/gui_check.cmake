# GUI tests under Xvfb, run as a user would: candela starts on a scene, is driven by its scriptable
# options, takes a screenshot and quits. Arguments: CLI, VIEWER, XVFB_RUN, COMPARE, SCENE, OUT, MODE,
# and BLENDER_VDB (the tool that writes a Blender-like Z-up VDB).
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
set(XVFB ${XVFB_RUN} -a -s "-screen 0 1500x820x24")
set(ENV{ASAN_OPTIONS} detect_leaks=0)  # Mesa leaks a few bytes at exit

# The value of KEY in a screenshot's metadata.
function(metadata image key var)
  execute_process(COMMAND ${COMPARE} --metadata ${image} ${key} OUTPUT_VARIABLE value RESULT_VARIABLE rc OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "no \"${key}\" in the metadata of ${image}")
  endif()
  set(${var} "${value}" PARENT_SCOPE)
endfunction()

function(expect_contains text expected)
  string(FIND "${text}" "${expected}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "expected \"${expected}\" in: ${text}")
  endif()
endfunction()

# Mean 8-bit level of the left half, the right half and the number of distinct levels of a PNG.
function(halves image left right levels)
  execute_process(COMMAND ${COMPARE} --halves ${image} OUTPUT_VARIABLE out RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0 OR NOT out MATCHES "left ([0-9.]+) right ([0-9.]+) mean [0-9.]+ levels ([0-9]+)")
    message(FATAL_ERROR "cannot read ${image}")
  endif()
  set(${left} ${CMAKE_MATCH_1} PARENT_SCOPE)
  set(${right} ${CMAKE_MATCH_2} PARENT_SCOPE)
  set(${levels} ${CMAKE_MATCH_3} PARENT_SCOPE)
endfunction()

# Runs a command that must exit 0 within `seconds` (a hang fails on the limit); its output goes to
# LAST_OUTPUT.
function(run_within seconds)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT ${seconds})
  message("${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}; the limit is ${seconds} s): ${ARGN}")
  endif()
  set(LAST_OUTPUT "${out}${err}" PARENT_SCOPE)
endfunction()

function(run_checked)
  run_within(240 ${ARGN})
  set(LAST_OUTPUT "${LAST_OUTPUT}" PARENT_SCOPE)
endfunction()

if(MODE STREQUAL "screenshot")
  # The viewer's screenshot against the CLI's render of the same scene, strategy, seed and spp.
  run_checked(${CLI} render ${SCENE} --strategy emission --spp 8 --set camera.resolution=[320,180] -o ${OUT}/cli.exr)
  run_checked(${XVFB} ${VIEWER} ${SCENE} --strategy emission --set camera.resolution=[320,180]
              --screenshot ${OUT}/gui.png --after-spp 8 --quit)
  run_checked(${COMPARE} ${OUT}/gui.png ${OUT}/gui.exr ${OUT}/cli.exr 8)
  # File > Open image: the CLI's EXR kept as a snapshot and compared with the live render.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --strategy emission --set camera.resolution=[320,180] --open-image ${OUT}/cli.exr
              --screenshot ${OUT}/opened.png --after-spp 4 --quit)
  expect_contains("${LAST_OUTPUT}" "opened ${OUT}/cli.exr as snapshot")
  metadata(${OUT}/opened-compare.png compared_snapshot snapshot)
  expect_contains("${snapshot}" "cli.exr")
  # A file that is not an EXR: a clear message; the render goes on and the screenshot is taken (the
  # scripted run exits 1 for the failed step).
  execute_process(COMMAND ${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --open-image ${SCENE} --screenshot ${OUT}/not-exr.png
                  --after-spp 2 --quit RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
  expect_contains("${out}${err}" "expected an OpenEXR image")
  if(NOT rc EQUAL 1 OR NOT EXISTS ${OUT}/not-exr.png)
    message(FATAL_ERROR "opening a scene file as an image: exit ${rc} (expected 1) and a screenshot still taken")
  endif()
elseif(MODE STREQUAL "inspect")
  # The guide inspector opened on a pixel as a Ctrl+click would: its chart's variance factors.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --strategy full --set camera.resolution=[160,90] --inspect 95,40
              --screenshot ${OUT}/inspect.png --after-spp 2 --quit)
  if(NOT LAST_OUTPUT MATCHES "inspector: pixel \\(95, 40\\), full, camera ray: .*guided [0-9.]+, tracked [0-9.]+, mis \\(guided share [0-9.]+\\) [0-9.]+")
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
       "${VIEWER} ${SCENE} --set camera.resolution=[160,90] --set display.exposure=0 --screenshot ${OUT}/$1.png --after 3 --quit &
        sleep 2.5
        if [ $1 = image ]; then xdotool mousemove 400 400 sleep 0.2 mousedown 1 sleep 0.2 mousemove 450 410 sleep 0.2 mousemove 520 420 sleep 0.2 mouseup 1; fi
        if [ $1 = panel ]; then xdotool mousemove 1300 600 sleep 0.2 mousedown 1 sleep 0.2 mousemove 1350 610 sleep 0.2 mousemove 1420 620 sleep 0.2 mouseup 1; fi
        if [ $1 = frame ]; then xdotool mousemove 400 400 sleep 0.2 key f; fi
        if [ $1 = keys ]; then xdotool mousemove 400 400 sleep 0.2 key --delay 1 e e e e e e e e c c c; fi
        wait $!
")
  foreach(case image panel frame keys)
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
  # Eight presses of E and three of C, as fast as xdotool types them: every press counts.
  metadata(${OUT}/keys.png display display)
  string(JSON exposure GET "${display}" exposure)
  string(JSON channel GET "${display}" channel)
  if(NOT exposure EQUAL 4 OR NOT channel STREQUAL "b")
    message(FATAL_ERROR "8 presses of E and 3 of C gave exposure ${exposure} (expected 4) and channel ${channel} (expected b)")
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
elseif(MODE STREQUAL "open_vdb")
  # Each shipped generator written to a .vdb and opened cold, then a Blender-like Z-up bake: the
  # grids are recognised, the camera frames the volume (a rendered image, not sky alone) and the
  # Z-up file is turned upright.
  foreach(type constant ramp torch mist cloud plume)
    run_checked(${CLI} generate ${type} --resolution 32 -o ${OUT}/${type}.vdb)
    run_checked(${XVFB} ${VIEWER} ${OUT}/${type}.vdb --set camera.resolution=[160,90] --screenshot ${OUT}/${type}.png --after-spp 4 --quit)
    expect_contains("${LAST_OUTPUT}" "first image:")
    metadata(${OUT}/${type}.png opened_volume opened)
    expect_contains("${opened}" "density \"density\"")
    expect_contains("${opened}" "Y-up")
    metadata(${OUT}/${type}.png document document)
    expect_contains("${document}" "${type}.json")
    # A ground plane under it catches its shadow.
    metadata(${OUT}/${type}.png settings settings)
    string(JSON ground GET "${settings}" surfaces 0 type)
    if(NOT ground STREQUAL "plane")
      message(FATAL_ERROR "${type}.vdb opened without a ground plane")
    endif()
    # Opened and not touched: nothing to save, so switching files or quitting asks nothing.
    metadata(${OUT}/${type}.png unsaved_edits unsaved)
    if(NOT unsaved STREQUAL "no")
      message(FATAL_ERROR "${type}.vdb opened and untouched reads as unsaved (${unsaved})")
    endif()
    halves(${OUT}/${type}.png left right levels)
    if(levels LESS 12)
      message(FATAL_ERROR "${type}: the opened volume shows only ${levels} levels: nothing rendered in frame?")
    endif()
  endforeach()
  run_checked(${BLENDER_VDB} ${OUT}/blender_fire.vdb)
  run_checked(${XVFB} ${VIEWER} ${OUT}/blender_fire.vdb --set camera.resolution=[160,90] --screenshot ${OUT}/blender.png --after-spp 4 --quit)
  metadata(${OUT}/blender.png opened_volume opened)
  expect_contains("${opened}" "Z-up")
  expect_contains("${opened}" "emission grid (per unit length) from \"flame\"")
  expect_contains("${opened}" "velocity (vec3s)")
  metadata(${OUT}/blender.png settings settings)
  string(JSON rotate GET "${settings}" volumes 0 transform rotate_deg 0)
  if(NOT rotate EQUAL -90)
    message(FATAL_ERROR "the Z-up file was not turned upright (rotate_deg.x ${rotate})")
  endif()
  # Headless, the same: candela-cli render VOLUME.vdb.
  run_checked(${CLI} render ${OUT}/blender_fire.vdb --spp 4 --set camera.resolution=[160,90] -o ${OUT}/blender-cli.exr)
  expect_contains("${LAST_OUTPUT}" "Z-up")
  # Dropped on the window: the same import.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --drop ${OUT}/cloud.vdb --screenshot ${OUT}/dropped.png
              --after-spp 4 --quit)
  metadata(${OUT}/dropped.png document document)
  expect_contains("${document}" "cloud.json")
  # Edited while it loads (each build held back a second): the edits stay on the opened file, and
  # auto exposure does not replace the exposure the artist set.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --drop ${OUT}/cloud.vdb --hold-builds 1000
              --edit-while-loading --edit render.seed=7 --edit display.exposure=1.25 --screenshot ${OUT}/dropped-edited.png
              --after-spp 4 --quit)
  expect_contains("${LAST_OUTPUT}" "scripted: 2 edits made while loading")
  metadata(${OUT}/dropped-edited.png document document)
  expect_contains("${document}" "cloud.json")
  metadata(${OUT}/dropped-edited.png settings settings)
  string(JSON seed GET "${settings}" render seed)
  metadata(${OUT}/dropped-edited.png display display)
  string(JSON exposure GET "${display}" exposure)
  metadata(${OUT}/dropped-edited.png unsaved_edits unsaved)
  if(NOT seed EQUAL 7 OR NOT exposure EQUAL 1.25 OR NOT unsaved STREQUAL "yes")
    message(FATAL_ERROR "edits made while the dropped file loaded were lost: seed ${seed}, exposure ${exposure}, unsaved edits ${unsaved}")
  endif()
  # Reset camera pressed while it loads goes to the dropped file's camera, not the old scene's.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --drop ${OUT}/cloud.vdb --hold-builds 1000
              --edit-while-loading --reset-camera --screenshot ${OUT}/dropped-reset.png --after-spp 4 --quit)
  expect_contains("${LAST_OUTPUT}" "scripted: 0 edits and a camera reset made while loading")
  metadata(${OUT}/dropped.png settings settings)
  string(JSON opened_camera GET "${settings}" camera)
  metadata(${OUT}/dropped-reset.png settings settings)
  string(JSON reset_camera GET "${settings}" camera)
  string(JSON same EQUAL "${opened_camera}" "${reset_camera}")
  if(NOT same)
    message(FATAL_ERROR "Reset camera during the load gave ${reset_camera}, not the dropped file's ${opened_camera}")
  endif()
  # A dropped scene whose VDB is missing fails to build: the document stays the scene that still
  # renders, so Save can never write it over the file that failed.
  get_filename_component(scenes ${SCENE} DIRECTORY)
  file(READ ${scenes}/cloud.json broken)
  string(JSON broken REMOVE "${broken}" volumes 0 generator)
  string(JSON broken SET "${broken}" volumes 0 file "\"missing-drop.vdb\"")
  file(WRITE ${OUT}/broken-drop.json "${broken}")
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --drop ${OUT}/broken-drop.json
              --screenshot ${OUT}/dropped-broken.png --after-spp 4 --quit)
  expect_contains("${LAST_OUTPUT}" "missing-drop.vdb")
  expect_contains("${LAST_OUTPUT}" "the document is still")
  metadata(${OUT}/dropped-broken.png document document)
  metadata(${OUT}/dropped-broken.png scene scene)
  if(document MATCHES "broken-drop" OR scene MATCHES "broken-drop")
    message(FATAL_ERROR "after a failed drop the document is the file that failed: ${document}, ${scene}")
  endif()
  # The same drop edited while it loads: the edits were edits of the file that failed, so they go
  # with it and the viewer says so; the look is the scene's that still renders, and the run does not
  # hang waiting for an image of the dropped edits (it did, with the edit-latency timer left running).
  run_within(60 ${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --drop ${OUT}/broken-drop.json --hold-builds 1000
             --edit-while-loading --edit render.seed=7 --edit display.exposure=1.25
             --screenshot ${OUT}/dropped-broken-edited.png --after-spp 4 --quit)
  expect_contains("${LAST_OUTPUT}" "scripted: 2 edits made while loading")
  expect_contains("${LAST_OUTPUT}" "the edits made while broken-drop.json loaded went with it")
  metadata(${OUT}/dropped-broken.png display display)
  string(JSON kept_exposure GET "${display}" exposure)
  metadata(${OUT}/dropped-broken.png settings settings)
  string(JSON kept_seed GET "${settings}" render seed)
  metadata(${OUT}/dropped-broken-edited.png display display)
  string(JSON exposure GET "${display}" exposure)
  metadata(${OUT}/dropped-broken-edited.png settings settings)
  string(JSON seed GET "${settings}" render seed)
  metadata(${OUT}/dropped-broken-edited.png document document)
  if(document MATCHES "broken-drop" OR NOT exposure EQUAL kept_exposure OR NOT seed EQUAL kept_seed)
    message(FATAL_ERROR "after a failed, edited drop: document ${document}, exposure ${exposure} (expected ${kept_exposure}), seed ${seed} (expected ${kept_seed})")
  endif()
  # A drop that cannot open at all (no such file; not JSON): the error names it, and the scene on
  # screen keeps its samples (no reload, no claim that its file changed on disk).
  file(WRITE ${OUT}/not-json.json "{ this is not a scene")
  foreach(bad ${OUT}/no-such-file.vdb ${OUT}/not-json.json)
    run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --drop ${bad} --screenshot ${OUT}/failed-drop.png
                --after 1.5 --quit)
    get_filename_component(name ${bad} NAME)
    expect_contains("${LAST_OUTPUT}" "could not open ${bad}")
    expect_contains("${LAST_OUTPUT}" "still showing the last good scene")
    if(LAST_OUTPUT MATCHES "reloading|changed on disk")
      message(FATAL_ERROR "a failed drop of ${name} reloaded the scene on screen")
    endif()
    metadata(${OUT}/failed-drop.png document document)
    if(NOT document STREQUAL "${SCENE}")
      message(FATAL_ERROR "after a failed drop of ${name} the document is ${document}")
    endif()
  endforeach()
elseif(MODE STREQUAL "relative")
  # Bare file names in the working folder, as `candela plume.vdb` is typed: open, Save As out.json,
  # then reopen out.json and Save As again; every path relative.
  run_checked(${CLI} generate plume --resolution 24 -o ${OUT}/plume.vdb)
  file(WRITE ${OUT}/relative.sh
       "cd ${OUT} && ${VIEWER} plume.vdb --set camera.resolution=[160,90] --save-as out.json --screenshot first.png --after-spp 4 --quit &&
        ${VIEWER} out.json --edit volumes.0.g=0.25 --save-as again.json --screenshot second.png --after-spp 4 --quit
")
  run_checked(${XVFB} sh ${OUT}/relative.sh)
  expect_contains("${LAST_OUTPUT}" "saved out.json")
  expect_contains("${LAST_OUTPUT}" "saved again.json")
  if(LAST_OUTPUT MATCHES "save failed|cannot make absolute")
    message(FATAL_ERROR "saving by a bare file name failed")
  endif()
  file(READ ${OUT}/again.json saved)
  string(JSON file GET "${saved}" volumes 0 file)
  string(JSON g GET "${saved}" volumes 0 g)
  if(NOT file STREQUAL "plume.vdb" OR NOT g MATCHES "^0\\.25")
    message(FATAL_ERROR "again.json: volume file ${file}, g ${g}")
  endif()
  # The opened VDB's exposure is saved as auto exposure chose it, or, saved before the first image
  # chose one, left out (auto again on reopening); never a 0 nobody chose.
  file(READ ${OUT}/out.json saved)
  string(JSON exposure ERROR_VARIABLE missing GET "${saved}" display exposure)
  metadata(${OUT}/first.png display display)
  string(JSON shown GET "${display}" exposure)
  message("out.json: exposure ${exposure}${missing}; shown ${shown}")
  if(NOT missing AND NOT exposure EQUAL shown)
    message(FATAL_ERROR "out.json saved exposure ${exposure}; the viewer showed ${shown}")
  endif()
elseif(MODE STREQUAL "exposure")
  # A shipped scene that gives no exposure opens exposed by its own image: the torch's handle, the
  # ground and the mist's glow read, not just the flame.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --screenshot ${OUT}/default.png --after-spp 8 --quit)
  expect_contains("${LAST_OUTPUT}" "auto exposure:")
  metadata(${OUT}/default.png display display)
  string(JSON exposure GET "${display}" exposure)
  halves(${OUT}/default.png left right levels)
  message("default view: exposure ${exposure}, mean levels left ${left} right ${right}")
  if(exposure LESS 1 OR left LESS 40 OR right LESS 40)
    message(FATAL_ERROR "the default view is dark: exposure ${exposure}, mean levels ${left} / ${right}")
  endif()
  # A scene that gives its exposure keeps it.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --set display.exposure=0.5 --screenshot ${OUT}/given.png
              --after-spp 4 --quit)
  metadata(${OUT}/given.png display display)
  string(JSON exposure GET "${display}" exposure)
  if(NOT exposure EQUAL 0.5)
    message(FATAL_ERROR "a scene's own exposure 0.5 was replaced by ${exposure}")
  endif()
  # A PNG sequence from the CLI: one exposure for every frame (the first frame's).
  foreach(f 1 2 3)
    run_checked(${CLI} generate plume --seed ${f} --resolution 32 -o ${OUT}/seq/fire.000${f}.vdb)
  endforeach()
  run_checked(${CLI} render ${OUT}/seq/fire.0001.vdb --frames 1-3 --spp 2 --set camera.resolution=[64,36] -o ${OUT}/png/fire.PNG)
  set(exposures "")
  foreach(f 1 2 3)
    metadata(${OUT}/png/fire.000${f}.PNG exposure e)
    list(APPEND exposures ${e})
  endforeach()
  list(REMOVE_DUPLICATES exposures)
  list(LENGTH exposures distinct)
  if(NOT distinct EQUAL 1 OR exposures STREQUAL "0.000000")
    message(FATAL_ERROR "a PNG sequence's frames got exposures ${exposures}: expected one auto exposure for all")
  endif()
elseif(MODE STREQUAL "comparison")
  # `candela` with no scene is the four-pane comparison, and a scripted screenshot keeps it: the
  # figure (panes and grid in its metadata) plus a PNG and an EXR per pane, exposed by one shared
  # auto exposure, each pane titled in words, auto with what it chose.
  run_checked(${XVFB} ${VIEWER} --set camera.resolution=[160,90] --screenshot ${OUT}/cmp.png --after-spp 4 --quit)
  expect_contains("${LAST_OUTPUT}" "auto exposure:")
  metadata(${OUT}/cmp.png grid grid)
  metadata(${OUT}/cmp.png panes panes)
  if(NOT grid STREQUAL "2x2")
    message(FATAL_ERROR "the default comparison's figure has grid ${grid}, expected 2x2")
  endif()
  string(JSON count LENGTH "${panes}")
  if(NOT count EQUAL 4)
    message(FATAL_ERROR "the figure names ${count} panes, expected 4: ${panes}")
  endif()
  string(JSON auto_title GET "${panes}" 3 title)
  expect_contains("${auto_title}" "auto: chose ")
  string(JSON estimated GET "${panes}" 0 error_estimated)
  if(NOT estimated)
    message(FATAL_ERROR "without a reference the panes carry no error estimate: ${panes}")
  endif()
  foreach(pane conventional emission full auto)
    foreach(ext png exr)
      if(NOT EXISTS ${OUT}/cmp-${pane}.${ext})
        message(FATAL_ERROR "missing ${OUT}/cmp-${pane}.${ext}")
      endif()
    endforeach()
    metadata(${OUT}/cmp-${pane}.png display display)
    string(JSON exposure GET "${display}" exposure)
    if(exposure LESS 1)
      message(FATAL_ERROR "pane ${pane} is shown at exposure ${exposure}: the comparison opened dark")
    endif()
  endforeach()
elseif(MODE STREQUAL "region")
  # A render region: only its pixels refine (to --after-spp), the rest of the image holds.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --region 60,10,40,50 --screenshot ${OUT}/region.png
              --after-spp 32 --quit)
  expect_contains("${LAST_OUTPUT}" "render region 40x50 at (60, 10)")
  metadata(${OUT}/region.png region region)
  metadata(${OUT}/region.png region_spp region_spp)
  metadata(${OUT}/region.png spp spp)
  if(NOT region STREQUAL "60,10,40,50" OR NOT region_spp EQUAL 32 OR NOT spp LESS 32)
    message(FATAL_ERROR "region ${region} at ${region_spp} spp, the rest at ${spp}: expected 60,10,40,50 at 32, the rest fewer")
  endif()
elseif(MODE STREQUAL "save")
  # Edit, save as, reopen: the reopened scene renders the same samples as the edited one.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --strategy emission --set camera.resolution=[160,90] --edit volumes.1.g=0.3
              --edit display.exposure=1.5 --save-as ${OUT}/looks/look.json --screenshot ${OUT}/edited.png --after-spp 8 --quit)
  expect_contains("${LAST_OUTPUT}" "saved ${OUT}/looks/look.json")
  metadata(${OUT}/edited.png unsaved_edits unsaved)
  metadata(${OUT}/edited.png document document)
  if(NOT unsaved STREQUAL "no" OR NOT document STREQUAL "${OUT}/looks/look.json")
    message(FATAL_ERROR "after the save: unsaved edits \"${unsaved}\", document \"${document}\"")
  endif()
  file(READ ${OUT}/looks/look.json saved)
  string(JSON g GET "${saved}" volumes 1 g)
  string(JSON exposure GET "${saved}" display exposure)
  if(NOT g MATCHES "^0\\.300" OR NOT exposure EQUAL 1.5)
    message(FATAL_ERROR "the saved scene lost edits: g ${g}, exposure ${exposure}")
  endif()
  run_checked(${XVFB} ${VIEWER} ${OUT}/looks/look.json --screenshot ${OUT}/reopened.png --after-spp 8 --quit)
  run_checked(${COMPARE} --same-exr ${OUT}/edited.exr ${OUT}/reopened.exr)
  metadata(${OUT}/reopened.png display display)
  expect_contains("${display}" "\"exposure\":1.5")
  # Under auto, a strategy field's edit takes auto's choice over (torch-in-mist: full, with its
  # relative emission weight and adaptive sampling) rather than editing auto's undecided settings.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --edit strategy.russian_roulette_depth=5
              --save-as ${OUT}/looks/taken-over.json --screenshot ${OUT}/taken-over.png --after-spp 4 --quit)
  file(READ ${OUT}/looks/taken-over.json saved)
  string(JSON preset GET "${saved}" strategy preset)
  string(JSON depth GET "${saved}" strategy russian_roulette_depth)
  string(JSON split GET "${saved}" strategy adaptive_split)
  string(JSON relative GET "${saved}" strategy majorant relative_weight)
  if(NOT preset STREQUAL "full" OR NOT depth EQUAL 5 OR NOT split EQUAL 8 OR NOT relative STREQUAL "ON")
    message(FATAL_ERROR "an edit under auto saved preset ${preset}, russian_roulette_depth ${depth}, adaptive_split ${split}, relative_weight ${relative}")
  endif()
elseif(MODE STREQUAL "undo")
  # Two edits, undo both, redo one: the first edit is back, the second is not.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --edit volumes.1.g=0.3 --edit volumes.1.sigma_t_scale=2
              --undo 2 --redo 1 --screenshot ${OUT}/undo.png --after-spp 4 --quit)
  metadata(${OUT}/undo.png settings settings)
  string(JSON g GET "${settings}" volumes 1 g)
  string(JSON sigma GET "${settings}" volumes 1 sigma_t_scale)
  metadata(${OUT}/undo.png undo_steps undo_steps)
  metadata(${OUT}/undo.png redo_steps redo_steps)
  message("after undo 2, redo 1: g ${g}, sigma_t_scale ${sigma}, ${undo_steps} undo and ${redo_steps} redo steps left")
  if(NOT g MATCHES "^0\\.300" OR NOT sigma MATCHES "^0\\.100" OR NOT undo_steps EQUAL 1 OR NOT redo_steps EQUAL 1)
    message(FATAL_ERROR "undo/redo did not restore the expected state")
  endif()
  # An edit whose scene cannot build (the file field pointed at a broken VDB): the scene and the
  # fields go back to the file that renders, and the run does not wait for an image of the failed
  # edit (it did, with the edit-latency timer left running). The failed state leaves the undo
  # history too (EditHistory.AFailedEditLeavesTheHistory): here the step stays, holding the state
  # that renders, since auto exposure and auto's decision changed it after the edit.
  run_checked(${CLI} generate cloud --resolution 16 -o ${OUT}/cloud.vdb)
  file(WRITE ${OUT}/broken.vdb "not a VDB")
  run_checked(${XVFB} ${VIEWER} ${OUT}/cloud.vdb --set camera.resolution=[160,90] --edit volumes.0.file=${OUT}/broken.vdb
              --screenshot ${OUT}/undo-failed.png --after-spp 4 --quit)
  expect_contains("${LAST_OUTPUT}" "broken.vdb")
  metadata(${OUT}/undo-failed.png undo_steps undo_steps)
  metadata(${OUT}/undo-failed.png settings settings)
  string(JSON file GET "${settings}" volumes 0 file)
  if(NOT file MATCHES "cloud.vdb$" OR undo_steps GREATER 1)
    message(FATAL_ERROR "after a failed edit: volume file ${file} (expected cloud.vdb), ${undo_steps} undo steps")
  endif()
elseif(MODE STREQUAL "snapshot")
  # A snapshot at 4 spp, then the exposure up 3 stops: the wipe shows the brighter live render left
  # of the divider and the snapshot, as it was seen, right of it.
  run_checked(${XVFB} ${VIEWER} ${SCENE} --set camera.resolution=[160,90] --set display.exposure=0 --snapshot-compare --edit display.exposure=3
              --screenshot ${OUT}/snap.png --after-spp 4 --quit)
  metadata(${OUT}/snap-compare.png compare_mode mode)
  metadata(${OUT}/snap-compare.png compared_snapshot snapshot)
  expect_contains("${mode}" "wipe")
  expect_contains("${snapshot}" "#1")
  halves(${OUT}/snap-compare.png left right levels)
  message("wipe: live (left) ${left}, snapshot (right) ${right}")
  if(NOT left GREATER right)
    message(FATAL_ERROR "the live half (+3 stops) is not brighter than the snapshot half")
  endif()
elseif(MODE STREQUAL "timeline")
  # A 3-frame sequence of 96^3 plumes: open frame 1, step twice; the shown frame is frame 3 and its
  # samples equal the CLI's render of frame 3.
  foreach(f 1 2 3)
    run_checked(${CLI} generate plume --seed ${f} --resolution 96 -o ${OUT}/seq/fire.000${f}.vdb)
  endforeach()
  run_checked(${XVFB} ${VIEWER} ${OUT}/seq/fire.0001.vdb --set camera.resolution=[160,90] --frame-steps 2
              --screenshot ${OUT}/timeline.png --after-spp 4 --quit)
  expect_contains("${LAST_OUTPUT}" "timeline: 2 steps")
  metadata(${OUT}/timeline.png frame frame)
  metadata(${OUT}/timeline.png frames frames)
  if(NOT frame EQUAL 3 OR NOT frames STREQUAL "1-3")
    message(FATAL_ERROR "timeline: shows frame ${frame} of ${frames}, expected 3 of 1-3")
  endif()
  run_checked(${CLI} render ${OUT}/seq/fire.0001.vdb --frames 1-3 --spp 4 --set camera.resolution=[160,90] -o ${OUT}/cli/fire.exr)
  foreach(f 1 2 3)
    if(NOT EXISTS ${OUT}/cli/fire.000${f}.exr)
      message(FATAL_ERROR "--frames 1-3 did not write ${OUT}/cli/fire.000${f}.exr")
    endif()
  endforeach()
  run_checked(${COMPARE} ${OUT}/timeline.png ${OUT}/timeline.exr ${OUT}/cli/fire.0003.exr 4)
  # File > Render sequence from the viewer: every frame written, each the CLI's render of it, and no
  # temporary file left beside them.
  run_checked(${XVFB} ${VIEWER} ${OUT}/seq/fire.0001.vdb --set camera.resolution=[160,90] --render-sequence "${OUT}/gui-seq/fire.####.exr"
              --after-spp 4 --quit)
  expect_contains("${LAST_OUTPUT}" "render sequence: wrote 3 of 3 frames")
  foreach(f 1 2 3)
    run_checked(${COMPARE} --same-exr ${OUT}/gui-seq/fire.000${f}.exr ${OUT}/cli/fire.000${f}.exr)
  endforeach()
  file(GLOB leftovers ${OUT}/gui-seq/.*partial*)
  if(leftovers)
    message(FATAL_ERROR "temporary files left: ${leftovers}")
  endif()
  # A sequence with a broken frame (a sim frame that failed to write), played: the viewer reports
  # the frame once and plays on past it, as a flipbook plays over a hole. It used to retry the frame
  # on every image (hundreds of the same error a second, the timeline stuck).
  file(MAKE_DIRECTORY ${OUT}/broken-seq)
  foreach(f 1 3)
    file(COPY_FILE ${OUT}/seq/fire.000${f}.vdb ${OUT}/broken-seq/fire.000${f}.vdb)
  endforeach()
  file(WRITE ${OUT}/broken-seq/fire.0002.vdb "not a VDB: the simulation stopped writing here")
  run_within(60 ${XVFB} ${VIEWER} ${OUT}/broken-seq/fire.0001.vdb --set camera.resolution=[160,90] --play
             --screenshot ${OUT}/broken-seq.png --after-spp 16 --quit)
  expect_contains("${LAST_OUTPUT}" "frame 2 could not be loaded (still on frame 1): Play and the step buttons pass it")
  expect_contains("${LAST_OUTPUT}" "frame 3: first image")
  string(REGEX MATCHALL "fire.0002.vdb: volumes" reports "${LAST_OUTPUT}")
  list(LENGTH reports count)
  if(count GREATER 1)
    message(FATAL_ERROR "the broken frame was reported ${count} times: playback kept retrying it")
  endif()
  if(LAST_OUTPUT MATCHES "playback paused")
    message(FATAL_ERROR "playback paused over one broken frame of three")
  endif()
  expect_contains("${LAST_OUTPUT}" "scripted: paused on frame 3")
  metadata(${OUT}/broken-seq.png frame frame)
  if(NOT frame EQUAL 3)
    message(FATAL_ERROR "playing past the broken frame 2 the viewer shows frame ${frame}, expected 3")
  endif()
  # The same sequence rendered as a batch: the broken frame is reported and passed, the others are
  # written, and the exit status (2, bad input) says one was not (it stopped at frame 2 and lost frame 3).
  execute_process(COMMAND ${CLI} render ${OUT}/broken-seq/fire.0001.vdb --frames 1-3 --spp 2 --set camera.resolution=[64,36]
                  -o ${OUT}/broken-cli/fire.exr RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
  message("${out}${err}")
  if(NOT rc EQUAL 2 OR NOT EXISTS ${OUT}/broken-cli/fire.0001.exr OR NOT EXISTS ${OUT}/broken-cli/fire.0003.exr
     OR EXISTS ${OUT}/broken-cli/fire.0002.exr)
    message(FATAL_ERROR "a batch over a broken frame: exit ${rc}, expected 2 with frames 1 and 3 written")
  endif()
  expect_contains("${err}" "1 of 3 frames could not be rendered (frames 2;")
  # A range past the sequence on disk is a mistyped range: said at once, nothing rendered.
  execute_process(COMMAND ${CLI} render ${OUT}/broken-seq/fire.0001.vdb --frames 1-100000 --spp 2 --set camera.resolution=[64,36]
                  -o ${OUT}/broken-range/fire.exr RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
  if(NOT rc EQUAL 2 OR EXISTS ${OUT}/broken-range/fire.0001.exr)
    message(FATAL_ERROR "--frames past the sequence: exit ${rc}, expected 2 before any frame")
  endif()
  expect_contains("${err}" "--frames 1-100000: the sequence on disk runs from frame 1 to 3 (3 files)")
  # Every other frame broken: playback pauses, once it has tried each, rather than spin on frame 1.
  file(MAKE_DIRECTORY ${OUT}/broken-seq-2)
  file(COPY_FILE ${OUT}/seq/fire.0001.vdb ${OUT}/broken-seq-2/fire.0001.vdb)
  foreach(f 2 3)
    file(WRITE ${OUT}/broken-seq-2/fire.000${f}.vdb "truncated")
  endforeach()
  run_within(60 ${XVFB} ${VIEWER} ${OUT}/broken-seq-2/fire.0001.vdb --set camera.resolution=[160,90] --play
             --screenshot ${OUT}/broken-seq-2.png --after-spp 16 --quit)
  expect_contains("${LAST_OUTPUT}" "playback paused: no other frame of the sequence could be loaded")
  metadata(${OUT}/broken-seq-2.png frame frame)
  if(NOT frame EQUAL 1)
    message(FATAL_ERROR "with frames 2 and 3 broken the viewer shows frame ${frame}, expected 1")
  endif()
elseif(MODE STREQUAL "quit_prompt")
  # Unsaved edits: Ctrl+Q asks instead of quitting; D (discard) then quits.
  file(WRITE ${OUT}/drive.sh
       "${VIEWER} ${SCENE} --set camera.resolution=[160,90] --edit volumes.1.g=0.5 &
        pid=$!
        sleep 3
        xdotool search --sync --name Candela >/dev/null; sleep 2
        xdotool mousemove 400 400 key ctrl+q
        sleep 2
        if ! kill -0 $pid 2>/dev/null; then echo 'QUIT WITHOUT ASKING'; exit 1; fi
        echo 'asked before quitting'
        xdotool key d
        for i in $(seq 1 40); do sleep 0.5; kill -0 $pid 2>/dev/null || break; done
        if kill -0 $pid 2>/dev/null; then echo 'STILL RUNNING AFTER DISCARD'; kill $pid; exit 1; fi
        wait $pid
")
  run_checked(${XVFB} sh ${OUT}/drive.sh)
  expect_contains("${LAST_OUTPUT}" "asked before quitting")
endif()
