# Worked examples of docs/architecture.md, "Extending sim4cv": each test is
# built from its test file and the one file that adds the thing it shows.
# sim4cv_extending_test(NAME EXAMPLE_FILE LIBS...)
function(sim4cv_extending_test name example)
  sim4cv_test(extending ${name} ${ARGN})
  target_sources(${name} PRIVATE extending/${example})
endfunction()

sim4cv_extending_test(extending_transport_test seqpacket_transport.cpp sim4cv_daemon)
sim4cv_extending_test(extending_entity_kind_test beacon_kind.cpp sim4cv_daemon)
