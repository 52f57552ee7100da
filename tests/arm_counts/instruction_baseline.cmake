# The ARM instruction counts as a regression check: each row of tests/arm_counts/rows (a stage,
# or the whole pipeline, of the simulated board's Aloe pair, one thread, the NEON kernels) run by
# epipole-bench under qemu-user with the project's counting plugin, for 1 and for 2 pairs: the
# difference is one pair's guest instructions, the set-up cancelled out. The test fails when a
# row's count is more than 5 % above the committed baseline of the preset. Counts are exact
# (what the guest executes, whatever the machine's load), so this is not a timing test.
#
# After a deliberate change, refresh the baseline and commit it (docs/performance.md):
#   EPIPOLE_ARM_COUNTS=update ctest --preset aarch64 -R arm_instruction_counts   (and armhf)
#
#   cmake -DEMULATOR=a|b|c -DPLUGIN=path -DBENCH=path -DBOARD=folder -DROWS=file
#         -DBASELINE=file -DPRESET=name -DOUT=folder -P this file
string(REPLACE "|" ";" emulator "${EMULATOR}")
set(tolerance_permille 50)

# count(VAR PAIRS STAGES [KEY=VALUE...] [scene=NAME] [--OPTION=VALUE]): the guest instructions
# of one whole epipole-bench run (of the Aloe pair unless the row names another scene).
function(count var pairs stages)
  set(scene aloe)
  set(settings)
  foreach(setting ${ARGN})
    if(setting MATCHES "^scene=(.+)$")
      set(scene ${CMAKE_MATCH_1})
    elseif(setting MATCHES "^--")
      list(APPEND settings ${setting})
    else()
      list(APPEND settings --set ${setting})
    endif()
  endforeach()
  set(args --board ${BOARD} --scene ${scene} --threads 1 --warmup 0 -n ${pairs} --no-opencv
           --json)
  if(NOT stages STREQUAL "all")
    list(APPEND args --stages ${stages})
  endif()
  list(APPEND args ${settings})
  set(file ${OUT}/arm-instructions-${pairs})
  file(REMOVE ${file})
  execute_process(COMMAND ${emulator} -plugin ${PLUGIN},out=${file} ${BENCH} ${args}
                  RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT status EQUAL 0 OR NOT EXISTS ${file})
    message(FATAL_ERROR "epipole-bench ${args} under the plugin: exit ${status}\n${err}")
  endif()
  string(JSON notes GET "${out}" notes)
  if(notes MATCHES "detect: off")
    message(FATAL_ERROR "epipole-bench ${args}: ${notes} (the host build compiles the cascades "
                        "into the data cache)")
  endif()
  file(STRINGS ${file} instructions)
  if(NOT instructions MATCHES "^[0-9]+$")
    message(FATAL_ERROR "the plugin wrote '${instructions}', not a count")
  endif()
  set(${var} ${instructions} PARENT_SCOPE)
endfunction()

file(STRINGS ${ROWS} lines REGEX "^[a-z]")
set(names)
foreach(line IN LISTS lines)
  string(REGEX REPLACE "[ \t]+" ";" fields "${line}")
  list(POP_FRONT fields name stages)
  count(once 1 ${stages} ${fields})
  count(twice 2 ${stages} ${fields})
  math(EXPR per_pair "${twice} - ${once}")
  if(per_pair LESS_EQUAL 0)
    message(FATAL_ERROR "${name}: ${once} instructions for 1 pair, ${twice} for 2")
  endif()
  set(count_${name} ${per_pair})
  list(APPEND names ${name})
endforeach()

if("$ENV{EPIPOLE_ARM_COUNTS}" STREQUAL "update")
  set(json "{\n  \"preset\": \"${PRESET}\",\n  \"unit\": \"guest instructions per pair\",\n  \"counts\": {")
  set(separator "")
  foreach(name IN LISTS names)
    string(APPEND json "${separator}\n    \"${name}\": ${count_${name}}")
    set(separator ",")
  endforeach()
  string(APPEND json "\n  }\n}\n")
  file(WRITE ${BASELINE} "${json}")
  message(STATUS "wrote ${BASELINE}:\n${json}")
  return()
endif()

if(NOT EXISTS ${BASELINE})
  message(FATAL_ERROR "no baseline ${BASELINE}: make it with "
                      "EPIPOLE_ARM_COUNTS=update ctest --preset ${PRESET} -R arm_instruction_counts")
endif()
file(READ ${BASELINE} baseline)
set(report "")
set(grown "")
foreach(name IN LISTS names)
  string(JSON base ERROR_VARIABLE missing GET "${baseline}" counts ${name})
  if(missing)
    string(APPEND grown " ${name} (not in the baseline)")
    string(APPEND report "\n  ${name}: ${count_${name}}, not in the baseline")
    continue()
  endif()
  math(EXPR change "(${count_${name}} - ${base}) * 1000 / ${base}")
  string(APPEND report "\n  ${name}: ${count_${name}} against ${base} (${change} per mille)")
  if(change GREATER tolerance_permille)
    string(APPEND grown " ${name}")
  endif()
endforeach()
message(STATUS "guest instructions per pair, ${PRESET}:${report}")
if(grown)
  message(FATAL_ERROR "more than 5 % above the baseline:${grown}. If the change is deliberate, "
                      "refresh it: EPIPOLE_ARM_COUNTS=update ctest --preset ${PRESET} -R "
                      "arm_instruction_counts, and commit ${BASELINE}")
endif()
