# One bounded libFuzzer run for ctest: cmake -DFUZZER=exe -DSEEDS=dir -DWORK=dir -DSECONDS=n
#   -DMAX_LEN=bytes -DTIMEOUT=s -DRSS_MB=mb -DSEED=n [-DDICT=file] [-DFINDINGS=dir] -P run_fuzzer.cmake
# New inputs go to WORK/corpus; the seed folder is only read. A crash, leak, timeout,
# out-of-memory or violated property fails the test and leaves the input in WORK.
# SEED other than 0: a repeatable run. It starts from the seed folder alone (WORK/corpus is
# emptied) with that random seed and a fixed scratch folder, so the same commit in the same
# folder runs the same inputs in the same order (a slower machine a prefix of them) and CI does
# not fail at random. Paths differ between checkouts and libFuzzer learns from the strings the
# target compares, so another folder may explore differently: a failing input is printed (hex).
# SEED 0: a new random seed and the corpus kept from earlier runs (exploration; scripts/fuzz.sh).
if(NOT SEED EQUAL 0)
  file(REMOVE_RECURSE ${WORK}/corpus)
endif()
file(MAKE_DIRECTORY ${WORK}/corpus)
# The target's scratch folder: the same path on every run (see fuzz_common.cpp), in memory.
get_filename_component(name ${WORK} NAME)
if(IS_DIRECTORY /dev/shm)
  set(ENV{VKLOC_FUZZ_SCRATCH} /dev/shm/vkloc_fuzz_ctest_${name})
else()
  set(ENV{VKLOC_FUZZ_SCRATCH} ${WORK}/scratch)
endif()
# Past findings first, as regression inputs: each must now pass (known findings only report).
if(FINDINGS AND IS_DIRECTORY ${FINDINGS})
  file(GLOB regressions ${FINDINGS}/*)
  if(regressions)
    execute_process(COMMAND ${FUZZER} -timeout=${TIMEOUT} -rss_limit_mb=${RSS_MB} ${regressions} RESULT_VARIABLE rc)
    if(NOT rc EQUAL 0)
      message(FATAL_ERROR "${FUZZER} fails on a past finding in ${FINDINGS} (${rc})")
    endif()
  endif()
endif()
set(args ${WORK}/corpus ${SEEDS} -max_total_time=${SECONDS} -timeout=${TIMEOUT} -rss_limit_mb=${RSS_MB}
  -max_len=${MAX_LEN} -artifact_prefix=${WORK}/ -print_final_stats=1 -seed=${SEED})
if(DICT)
  list(APPEND args -dict=${DICT})
endif()
execute_process(COMMAND ${FUZZER} ${args} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  file(GLOB found ${WORK}/crash-* ${WORK}/leak-* ${WORK}/timeout-* ${WORK}/oom-* ${WORK}/slow-unit-*)
  # The input's bytes go into the log too, for a CI run whose build folder is gone.
  foreach(input ${found})
    file(READ ${input} bytes LIMIT 4096 HEX)
    message("${input} (hex, first 4096 bytes): ${bytes}")
  endforeach()
  message(FATAL_ERROR "${FUZZER} failed (${rc}); inputs: ${found}")
endif()
