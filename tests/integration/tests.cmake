# One line per integration test (real sim4cvd on loopback): sim4cv_test(integration NAME LIBS...)
sim4cv_test(integration handshake_test sim4cv_client)
