# epipole-bench as a board runs it (under qemu-user in a cross build): the simulated board's Aloe
# pair through every stage of both sides at 1 and 2 threads, as JSON, checked; OpenCV's side
# alone; some stages only; a key of the board set by --set; then a board that does not exist and
# an unknown option, each with its exit status.
# Timings are only checked to be there, never against a bound.
#
#   cmake -DBENCH=path [-DEMULATOR=a|b|c] -DBOARD=folder [-DKERNELS=neon] -P this file
string(REPLACE "|" ";" emulator "${EMULATOR}")

function(run_bench)
  execute_process(COMMAND ${emulator} ${BENCH} ${ARGN} RESULT_VARIABLE status
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  set(status ${status} PARENT_SCOPE)
  set(out "${out}" PARENT_SCOPE)
  set(err "${err}" PARENT_SCOPE)
endfunction()

# expect(WHAT condition...): fails with WHAT and the bench's output unless the condition holds.
function(expect what)
  if(NOT (${ARGN}))
    message(FATAL_ERROR "epipole-bench: ${what}\n${out}\n${err}")
  endif()
endfunction()

run_bench(--board ${BOARD} --scene aloe -n 1 --warmup 0 --threads 1,2 --json)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "epipole-bench exited with ${status}\n${out}\n${err}")
endif()
string(JSON width GET "${out}" width)
string(JSON kernels GET "${out}" kernels)
string(JSON runs LENGTH "${out}" runs)
expect("width ${width}, expected 640" width EQUAL 640)
if(KERNELS)
  expect("kernels ${kernels}, expected ${KERNELS}" kernels STREQUAL KERNELS)
endif()
expect("${runs} runs, expected 2 (1 and 2 threads)" runs EQUAL 2)
foreach(run 0 1)
  math(EXPR threads "${run} + 1")
  string(JSON got GET "${out}" runs ${run} threads)
  expect("run ${run} is for ${got} threads" got EQUAL threads)
  foreach(side epipole opencv)
    string(JSON rate GET "${out}" runs ${run} ${side} pairs_per_second)
    expect("${side} at ${threads} threads: ${rate} pairs/s" rate GREATER 0)
    set(stages rectify corners disparity detect)
    if(side STREQUAL "epipole")
      list(APPEND stages sparse)
    endif()
    foreach(stage ${stages})
      string(JSON p50 ERROR_VARIABLE missing GET "${out}" runs ${run} ${side} stages ${stage} p50_ms)
      expect("${side} has no ${stage} stage at ${threads} threads" NOT missing)
      expect("${side} ${stage}: ${p50} ms" p50 GREATER 0)
    endforeach()
  endforeach()
  # What the firmware found on Aloe (a rich scene: corners and matches by the hundred).
  string(JSON corners GET "${out}" runs ${run} epipole found corners)
  string(JSON matches GET "${out}" runs ${run} epipole found matches)
  expect("${corners} corners at ${threads} threads" corners GREATER 1000)
  expect("${matches} sparse matches at ${threads} threads" matches GREATER 100)
endforeach()

# One side only, as the ARM instruction counts run it.
run_bench(--board ${BOARD} --scene aloe -n 1 --warmup 0 --threads 1 --opencv-only --json)
expect("--opencv-only: exit ${status}" status EQUAL 0)
string(JSON rate ERROR_VARIABLE missing GET "${out}" runs 0 opencv pairs_per_second)
expect("--opencv-only: no OpenCV figures" NOT missing)
string(JSON ours ERROR_VARIABLE missing GET "${out}" runs 0 epipole)
expect("--opencv-only: the firmware's side ran too" missing)

# Some stages only.
run_bench(--board ${BOARD} --scene aloe -n 1 --warmup 0 --threads 1 --stages corners --json)
expect("--stages corners: exit ${status}" status EQUAL 0)
foreach(side epipole opencv)
  string(JSON stages GET "${out}" runs 0 ${side} stages)
  string(JSON count LENGTH "${stages}")
  string(JSON p50 ERROR_VARIABLE missing GET "${stages}" corners p50_ms)
  expect("--stages corners: ${side} ran ${stages}" count EQUAL 1 AND NOT missing)
endforeach()
run_bench(--stages colour)
expect("--stages colour: exit ${status}, expected 2 (usage)" status EQUAL 2)

# A key of the board set over its file's: block matching instead of SGM, on both sides.
run_bench(--board ${BOARD} --scene aloe -n 1 --warmup 0 --threads 1 --stages disparity
          --set stereo.method=bm --json)
expect("--set stereo.method=bm: exit ${status}" status EQUAL 0)
string(JSON method GET "${out}" method)
string(JSON set GET "${out}" set 0)
expect("--set stereo.method=bm: method ${method}, set ${set}"
       method STREQUAL "bm" AND set STREQUAL "stereo.method=bm")
run_bench(--board ${BOARD} -n 1 --set stereo.method=fast)
expect("--set stereo.method=fast: exit ${status}, expected 1" status EQUAL 1)
expect("--set stereo.method=fast: '${err}'" err MATCHES "stereo.method")
run_bench(--board ${BOARD} -n 1 --set stereo)
expect("--set stereo: exit ${status}, expected 1" status EQUAL 1)
expect("--set stereo: '${err}'" err MATCHES "is not KEY=VALUE")

run_bench(--board ${BOARD}/no-such-board -n 1)
expect("a board that does not exist: exit ${status}, expected 1" status EQUAL 1)
expect("a board that does not exist: '${err}'" err MATCHES "^epipole-bench: .*no-such-board")
run_bench(--pairs 0)
expect("--pairs 0: exit ${status}, expected 2 (usage)" status EQUAL 2)
