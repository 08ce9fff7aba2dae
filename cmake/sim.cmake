# Ship IMU simulator (core library without ROS; see docs/simulator.md).
add_library(${PROJECT_NAME}_sim
  src/sim/random.cpp
  src/sim/scenario.cpp
  src/sim/effects.cpp
  src/sim/motion.cpp
  src/sim/simulator.cpp)
target_include_directories(${PROJECT_NAME}_sim PUBLIC include)
target_link_libraries(${PROJECT_NAME}_sim PUBLIC Eigen3::Eigen yaml-cpp)

# The ROS messages of a simulator sample, shared by simulate_imu and simulator_node.
add_library(${PROJECT_NAME}_sim_ros src/ros/sim_messages.cpp)
target_include_directories(${PROJECT_NAME}_sim_ros PUBLIC include ${catkin_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_sim_ros PUBLIC ${PROJECT_NAME}_sim ${catkin_LIBRARIES})

# Command-line front end: scenario -> bag (and CSV), no ROS master needed.
add_executable(simulate_imu src/tools/simulate_imu.cpp)
target_include_directories(simulate_imu PRIVATE ${catkin_INCLUDE_DIRS})
target_link_libraries(simulate_imu ${PROJECT_NAME}_sim_ros ${PROJECT_NAME}_tools)

# Live publisher on simulated time (thin: only calls the sim library).
add_executable(simulator_node src/ros/simulator_node.cpp)
target_include_directories(simulator_node PRIVATE ${catkin_INCLUDE_DIRS})
target_link_libraries(simulator_node ${PROJECT_NAME}_sim_ros)

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(test_sim
    test/sim/main.cpp
    test/sim/test_scenario.cpp
    test/sim/test_effects.cpp
    test/sim/test_motion.cpp
    test/sim/test_determinism.cpp
    test/sim/test_random.cpp
    test/sim/test_shipped_scenarios.cpp)
  target_link_libraries(test_sim ${PROJECT_NAME}_sim)
  target_precompile_headers(test_sim PRIVATE <gtest/gtest.h> <cmath> <string> <vector>
                            "${CMAKE_CURRENT_SOURCE_DIR}/include/periodic_bias_compensation/sim/simulator.h")
  target_compile_definitions(test_sim PRIVATE
    PBC_SCENARIO_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config/scenarios")
endif()
