# Read by ctest (tests/CMakeLists.txt) after the discovered tests: tests that run with no other
# test beside them.
set_tests_properties(Renderer.TheAmbientViewIsTheShIrradianceOverPi PROPERTIES RUN_SERIAL TRUE)
