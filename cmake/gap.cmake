# Sim-to-real gap diagnosis (library without ROS, see docs/gap.md), its command-line tools,
# and the end-to-end test that every shipped scenario's bag is consumed by compensate_bag.

if(CATKIN_ENABLE_TESTING)
  # Issue 3: simulate_imu -> compensate_bag on every file of config/scenarios (60 s each).
  catkin_add_gtest(test_shipped_bags test/tools/test_shipped_bags.cpp)
  target_include_directories(test_shipped_bags PRIVATE include ${catkin_INCLUDE_DIRS})
  target_link_libraries(test_shipped_bags ${catkin_LIBRARIES})
  target_compile_definitions(test_shipped_bags PRIVATE
    PBC_SIMULATE_IMU="$<TARGET_FILE:simulate_imu>"
    PBC_COMPENSATE_BAG="$<TARGET_FILE:compensate_bag>"
    PBC_SCENARIO_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config/scenarios")
  add_dependencies(test_shipped_bags simulate_imu compensate_bag)
endif()
