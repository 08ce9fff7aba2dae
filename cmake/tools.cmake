# Offline tools on the cores (no ROS master); evaluate_compensator reads other estimators' bags.
add_executable(evaluate_compensator src/tools/evaluate_compensator.cpp)
target_link_libraries(evaluate_compensator ${PROJECT_NAME}_core ${PROJECT_NAME}_sim ${catkin_LIBRARIES})

# Speed benchmark of the core (Google Benchmark); run by scripts/bench, not a test.
find_package(benchmark QUIET)
if(benchmark_FOUND)
  add_executable(core_benchmark EXCLUDE_FROM_ALL test/bench/core_benchmark.cpp)
  target_link_libraries(core_benchmark ${PROJECT_NAME}_core ${PROJECT_NAME}_sim benchmark::benchmark)
  target_compile_definitions(core_benchmark PRIVATE PBC_SCENARIO_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config/scenarios")
endif()

# Speed of the ROS side (scripts/bench, not tests): the nodelet's input rate and latency, in the
# same manager as a publisher or as a separate process, and the floor of compensate_bag's speed.
add_executable(nodelet_benchmark EXCLUDE_FROM_ALL test/bench/nodelet_benchmark.cpp)
target_link_libraries(nodelet_benchmark ${PROJECT_NAME}_sim_ros ${catkin_LIBRARIES})
add_dependencies(nodelet_benchmark ${PROJECT_NAME}_nodelet compensator_node)
add_executable(bag_read_floor EXCLUDE_FROM_ALL test/bench/bag_read_floor.cpp)
target_link_libraries(bag_read_floor ${catkin_LIBRARIES})

if(CATKIN_ENABLE_TESTING)
  # The tools' shared command-line parser (header only, no ROS).
  catkin_add_gtest(test_command_line test/core/main.cpp test/tools/test_command_line.cpp)
endif()
