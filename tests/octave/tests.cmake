# The Octave/MATLAB client (clients/matlab) against the real daemon: client_test.m over
# TCP, UDP and shared memory, and the MOSSE tracker example in the loop (tests/octave/run.sh).
if(TARGET sim4cv_octave)
  add_test(NAME octave_client_test COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/octave/run.sh ${PROJECT_BINARY_DIR})
  set_tests_properties(octave_client_test PROPERTIES TIMEOUT ${SIM4CV_TEST_TIMEOUT} LABELS octave ENVIRONMENT "${SIM4CV_TEST_ENV}")
  if(SIM4CV_ASAN)
    # Octave itself is not built with ASan: the MEX file needs the runtimes preloaded, and Octave's
    # own allocations at exit are not ours (leaks go unchecked in this one test; the others check the daemon's).
    execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=libasan.so OUTPUT_VARIABLE asan_runtime
                    OUTPUT_STRIP_TRAILING_WHITESPACE)
    execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=libubsan.so OUTPUT_VARIABLE ubsan_runtime
                    OUTPUT_STRIP_TRAILING_WHITESPACE)
    set_property(TEST octave_client_test APPEND PROPERTY ENVIRONMENT
                 "LD_PRELOAD=${asan_runtime} ${ubsan_runtime};ASAN_OPTIONS=detect_leaks=0")
  endif()
  if(SIM4CV_TSAN)
    # Likewise for ThreadSanitizer's runtime, for Octave only (bash does not start with it preloaded).
    execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=libtsan.so OUTPUT_VARIABLE tsan_runtime
                    OUTPUT_STRIP_TRAILING_WHITESPACE)
    set_property(TEST octave_client_test APPEND PROPERTY ENVIRONMENT "OCTAVE_PRELOAD=${tsan_runtime}")
  endif()
endif()
