# The instruction-counting plugin under qemu-user: the probe's counts for N, 2N and 3N loop runs
# step by the same amount (the count is exact: nothing of the machine's load gets in), a multiple
# of N; an unknown plugin argument stops QEMU.
#
#   cmake -DEMULATOR=a|b|c -DPLUGIN=path -DPROBE=path -DOUT=folder -P this file
string(REPLACE "|" ";" emulator "${EMULATOR}")
set(n 1000)
set(counts)
foreach(times 1 2 3)
  math(EXPR runs "${n} * ${times}")
  set(file ${OUT}/insn-count-${runs})
  file(REMOVE ${file})
  execute_process(COMMAND ${emulator} -plugin ${PLUGIN},out=${file} ${PROBE} ${runs}
                  RESULT_VARIABLE status ERROR_VARIABLE err)
  if(NOT status EQUAL 0 OR NOT EXISTS ${file})
    message(FATAL_ERROR "insn_count_probe ${runs} under the plugin: exit ${status}\n${err}")
  endif()
  file(STRINGS ${file} count)
  if(NOT count MATCHES "^[0-9]+$")
    message(FATAL_ERROR "the plugin wrote '${count}', not a count")
  endif()
  list(APPEND counts ${count})
endforeach()
list(GET counts 0 c1)
list(GET counts 1 c2)
list(GET counts 2 c3)
math(EXPR step1 "${c2} - ${c1}")
math(EXPR step2 "${c3} - ${c2}")
math(EXPR per_run "${step1} / ${n}")
math(EXPR rest "${step1} % ${n}")
message(STATUS "guest instructions: ${c1}, ${c2}, ${c3}: ${per_run} a loop run")
if(NOT step1 EQUAL step2 OR step1 LESS_EQUAL 0 OR NOT rest EQUAL 0)
  message(FATAL_ERROR "the counts ${c1}, ${c2}, ${c3} do not grow by one multiple of ${n}")
endif()

execute_process(COMMAND ${emulator} -plugin ${PLUGIN},colour=blue ${PROBE} 1
                RESULT_VARIABLE status ERROR_VARIABLE err)
if(status EQUAL 0 OR NOT err MATCHES "unknown argument")
  message(FATAL_ERROR "an unknown plugin argument: exit ${status}\n${err}")
endif()
