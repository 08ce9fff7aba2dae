# Sim-to-real gap diagnosis (library without ROS, see docs/gap.md), its command-line tools,
# and the end-to-end test that every shipped scenario's bag is consumed by compensate_bag.
add_library(${PROJECT_NAME}_gap
  src/gap/signal.cpp
  src/gap/motion.cpp
  src/gap/csv.cpp
  src/gap/features.cpp
  src/gap/fit.cpp
  src/gap/diagnose.cpp
  src/gap/truth.cpp
  src/gap/stages.cpp)
target_include_directories(${PROJECT_NAME}_gap PUBLIC include)
target_link_libraries(${PROJECT_NAME}_gap PUBLIC ${PROJECT_NAME}_sim ${PROJECT_NAME}_core Eigen3::Eigen PkgConfig::FFTW3
  nlohmann_json::nlohmann_json)
target_precompile_headers(${PROJECT_NAME}_gap PRIVATE <algorithm> <cmath> <string> <vector> <Eigen/Dense>)

# validate_gap: the diagnosis on simulated recordings whose effect is withheld (no ROS).
add_executable(validate_gap src/tools/validate_gap.cpp)
target_link_libraries(validate_gap ${PROJECT_NAME}_gap ${PROJECT_NAME}_tools)

# diagnose_gap: a bag (rosbag C++ API) or a CSV against a scenario -> report.json/.md and plots.
add_executable(diagnose_gap src/tools/diagnose_gap.cpp)
target_include_directories(diagnose_gap PRIVATE include ${catkin_INCLUDE_DIRS})
# The ROS wrapper library for its bag check (ros/bag_check.h).
target_link_libraries(diagnose_gap ${PROJECT_NAME}_gap ${PROJECT_NAME}_ros ${PROJECT_NAME}_tools ${catkin_LIBRARIES})
target_compile_definitions(diagnose_gap PRIVATE PBC_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")

if(CATKIN_ENABLE_TESTING)
  # simulate_imu -> compensate_bag on every file of config/scenarios (60 s each).
  catkin_add_gtest(test_shipped_bags test/tools/test_shipped_bags.cpp)
  target_include_directories(test_shipped_bags PRIVATE include ${catkin_INCLUDE_DIRS})
  target_link_libraries(test_shipped_bags ${catkin_LIBRARIES})
  target_compile_definitions(test_shipped_bags PRIVATE
    PBC_SIMULATE_IMU="$<TARGET_FILE:simulate_imu>"
    PBC_COMPENSATE_BAG="$<TARGET_FILE:compensate_bag>"
    PBC_SCENARIO_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config/scenarios")
  add_dependencies(test_shipped_bags simulate_imu compensate_bag)

  # Gap library units, diagnosis on simulated cases, validate_gap --small, the CLI on a bag and
  # a CSV, and one real set when ../shared/data exists beside the repository (skipped otherwise).
  catkin_add_gtest(test_gap test/gap/test_gap.cpp test/gap/test_csv.cpp test/gap/test_motion_stage.cpp TIMEOUT 900)
  target_link_libraries(test_gap ${PROJECT_NAME}_gap)
  target_compile_definitions(test_gap PRIVATE
    PBC_VALIDATE_GAP="$<TARGET_FILE:validate_gap>"
    PBC_DIAGNOSE_GAP="$<TARGET_FILE:diagnose_gap>"
    PBC_SIMULATE_IMU="$<TARGET_FILE:simulate_imu>"
    PBC_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")
  add_dependencies(test_gap validate_gap diagnose_gap simulate_imu)

  # simulator_node on simulated time feeding compensator.launch: odometry/filtered arrives.
  add_rostest_gtest(test_simulator_compensator test/tools/simulator_compensator.test
    test/tools/simulator_compensator.cpp)
  target_include_directories(test_simulator_compensator PRIVATE ${catkin_INCLUDE_DIRS})
  target_link_libraries(test_simulator_compensator ${catkin_LIBRARIES})
  add_dependencies(test_simulator_compensator simulator_node compensator_node)
endif()
