# The tools' output files (temporary name, rename when complete, removed on a signal or an
# error; never over an input), no ROS. Every tool that writes files links it (also those of
# sim.cmake, ros.cmake and gap.cmake).
add_library(${PROJECT_NAME}_tools src/tools/output_file.cpp)
target_include_directories(${PROJECT_NAME}_tools PUBLIC include)

# The accuracy of estimates against the simulator's truth (evaluate_compensator's tables), no ROS.
add_library(${PROJECT_NAME}_metrics src/tools/metrics.cpp)
target_include_directories(${PROJECT_NAME}_metrics PUBLIC include)
target_link_libraries(${PROJECT_NAME}_metrics PUBLIC ${PROJECT_NAME}_core ${PROJECT_NAME}_sim)

# Offline tools on the cores (no ROS master); evaluate_compensator reads other estimators' bags.
add_executable(evaluate_compensator src/tools/evaluate_compensator.cpp)
target_link_libraries(evaluate_compensator ${PROJECT_NAME}_metrics ${PROJECT_NAME}_core ${PROJECT_NAME}_sim
  ${PROJECT_NAME}_tools ${catkin_LIBRARIES})

# Speed benchmark of the core (Google Benchmark); run by scripts/bench.py, not a test.
find_package(benchmark QUIET)
if(benchmark_FOUND)
  add_executable(core_benchmark EXCLUDE_FROM_ALL test/bench/core_benchmark.cpp)
  target_link_libraries(core_benchmark ${PROJECT_NAME}_core ${PROJECT_NAME}_sim benchmark::benchmark)
  target_compile_definitions(core_benchmark PRIVATE PBC_SCENARIO_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config/scenarios")
endif()
# The time of each sample's call, paced (scripts/bench.py, not a test).
add_executable(core_latency EXCLUDE_FROM_ALL test/bench/core_latency.cpp)
target_link_libraries(core_latency ${PROJECT_NAME}_core ${PROJECT_NAME}_sim)

# Speed of the ROS side (scripts/bench.py, not tests): the nodelet's input rate and latency, in the
# same manager as a publisher or as a separate process, and the floor of compensate_bag's speed.
add_executable(nodelet_benchmark EXCLUDE_FROM_ALL test/bench/nodelet_benchmark.cpp)
target_link_libraries(nodelet_benchmark ${PROJECT_NAME}_sim_ros ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(nodelet_benchmark ${PROJECT_NAME}_nodelet compensator_node)
add_executable(bag_read_floor EXCLUDE_FROM_ALL test/bench/bag_read_floor.cpp)
target_link_libraries(bag_read_floor ${catkin_LIBRARIES})
# The machine's own floor under the nodelet's latencies: thread wake-ups, timers, a spinning thread.
add_executable(wakeup_floor EXCLUDE_FROM_ALL test/bench/wakeup_floor.cpp)
target_link_libraries(wakeup_floor ${PROJECT_NAME}_ros)

if(CATKIN_ENABLE_TESTING)
  # The renderer of docs/benchmarks.md (test/bench/bench_render.py) on a small JSON fixture: a
  # Python unittest that writes its own JUnit XML (run by scripts/test like the gtests).
  # run_tests.py takes each COMMAND argument as one shell command line, hence the one string.
  catkin_run_tests_target(pyunit test_bench_render pyunit-test_bench_render.xml
    COMMAND "/usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/bench/test_bench_render.py --xunit ${CATKIN_TEST_RESULTS_DIR}/${PROJECT_NAME}/pyunit-test_bench_render.xml")
  # scripts/wave_hindsight.py's lever arm and hindsight FIR on streams of known answer.
  catkin_run_tests_target(pyunit test_wave_hindsight pyunit-test_wave_hindsight.xml
    COMMAND "/usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/bench/test_wave_hindsight.py --xunit ${CATKIN_TEST_RESULTS_DIR}/${PROJECT_NAME}/pyunit-test_wave_hindsight.xml")
  # scripts/bench_external.py's comparison with the frequency-domain estimate (held outputs).
  catkin_run_tests_target(pyunit test_bench_external pyunit-test_bench_external.xml
    COMMAND "/usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/bench/test_bench_external.py --xunit ${CATKIN_TEST_RESULTS_DIR}/${PROJECT_NAME}/pyunit-test_bench_external.xml")
  # The tools' shared command line (parser, header only) and output files: the helper itself,
  # then each tool that writes files run as a program (same file as an input refused, a signal
  # or an unwritable directory leaves nothing behind and names the output).
  catkin_add_gtest(test_command_line test/core/main.cpp test/tools/test_command_line.cpp
    test/tools/test_output_files.cpp)
  target_link_libraries(test_command_line ${PROJECT_NAME}_tools)
  target_compile_definitions(test_command_line PRIVATE
    PBC_SIMULATE_IMU="$<TARGET_FILE:simulate_imu>"
    PBC_COMPENSATE_BAG="$<TARGET_FILE:compensate_bag>"
    PBC_DIAGNOSE_GAP="$<TARGET_FILE:diagnose_gap>"
    PBC_VALIDATE_GAP="$<TARGET_FILE:validate_gap>"
    PBC_EVALUATE_COMPENSATOR="$<TARGET_FILE:evaluate_compensator>"
    PBC_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")
  add_dependencies(test_command_line simulate_imu compensate_bag diagnose_gap validate_gap evaluate_compensator)
  # The metrics on synthetic runs with known answers (no ROS, no simulator run).
  catkin_add_gtest(test_metrics test/core/main.cpp test/tools/test_metrics.cpp)
  target_link_libraries(test_metrics ${PROJECT_NAME}_metrics)
endif()
