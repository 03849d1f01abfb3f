# `candela-cli render --strategy auto` charges auto its pilot: the summary's work per sample is the
# pilot's work plus the render's over the image's samples, and says so. On god-rays the pilot renders
# guided candidates at about 1.1-1.2x the plain candidate's work (their continuations only on rays
# thinner than 0.5 optical depths), so auto, which keeps the plain candidate there, must show at
# least 5% more work per sample than the plain candidate rendered alone (7.6% at this seed).
# Seed 2: at 48x27 each candidate's pilot image holds 8 spp, and on seed 1 (of seeds 1-8) a fresh
# round put `full, by region` ahead, whose own work would pass this check without any pilot.
function(work_per_sample out var)
  if(NOT out MATCHES "work per sample ([0-9.e+-]+)")
    message(FATAL_ERROR "no work per sample in: ${out}")
  endif()
  set(${var} ${CMAKE_MATCH_1} PARENT_SCOPE)
endfunction()
set(common ${SCENE} --set camera.resolution=[48,27] --spp 64 --seed 2 --threads 2)
execute_process(COMMAND ${CLI} render ${common} --strategy auto -o ${OUT}/auto.exr RESULT_VARIABLE rc OUTPUT_VARIABLE auto ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "render --strategy auto failed (${rc}): ${auto} ${err}")
endif()
if(NOT auto MATCHES "auto chose conventional, gathering" OR NOT auto MATCHES "pilot \\(")
  message(FATAL_ERROR "expected a pilot that keeps the plain candidate: ${auto}")
endif()
if(NOT auto MATCHES "work per sample [0-9.e+-]+ \\(the pilot's included\\)")
  message(FATAL_ERROR "auto's work per sample does not say it includes the pilot: ${auto}")
endif()
execute_process(COMMAND ${CLI} render ${common} --strategy conventional --set strategy.emission.gather_every_collision=true
                -o ${OUT}/plain.exr RESULT_VARIABLE rc OUTPUT_VARIABLE plain ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "render of the plain candidate failed (${rc}): ${plain} ${err}")
endif()
if(plain MATCHES "pilot's included")
  message(FATAL_ERROR "a preset has no pilot to include: ${plain}")
endif()
work_per_sample("${auto}" auto_work)
work_per_sample("${plain}" plain_work)
# At least 5% more: without the pilot the two differ only by the tracking's own noise (well under 1%).
string(REGEX REPLACE "\\..*" "" plain_whole "${plain_work}")
math(EXPR plain_bound "${plain_whole} * 105 / 100")
if(NOT auto_work GREATER plain_bound)
  message(FATAL_ERROR "auto's work per sample (${auto_work}) should exceed the plain candidate's (${plain_work}) by 5%: its pilot is not charged")
endif()
message(STATUS "work per sample: auto ${auto_work} (pilot included), plain ${plain_work}")
