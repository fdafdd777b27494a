# The Octave/MATLAB client (clients/matlab) against the real daemon: client_test.m over
# TCP, UDP and shared memory, and the MOSSE tracker example in the loop (tests/octave/run.sh).
if(TARGET sim4cv_octave)
  add_test(NAME octave_client_test COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/octave/run.sh ${PROJECT_BINARY_DIR})
  set_tests_properties(octave_client_test PROPERTIES TIMEOUT 180 LABELS octave ENVIRONMENT "${SIM4CV_TEST_ENV}")
endif()
