# ROS wrapper, nodelet, node, offline bag tools and rostests.
include_directories(include ${catkin_INCLUDE_DIRS})

# Parameters: the wrapper's table, the readers (parameter server, YAML), the reconfigure message
# glue and the text generated from the tables. Apart from the wrapper so that parameter_docs
# builds without the code generated from cfg/Compensator.cfg, which it writes.
add_library(${PROJECT_NAME}_parameters
  src/ros/parameters.cpp
  src/ros/parameter_reference.cpp)
target_link_libraries(${PROJECT_NAME}_parameters ${PROJECT_NAME}_core ${catkin_LIBRARIES} yaml-cpp)

# Wrapper library: message conversions, the IMU mounting, the CompensatorRos class, the bag reader,
# writer and check of the offline tools.
add_library(${PROJECT_NAME}_ros
  src/ros/conversions.cpp
  src/ros/mounting.cpp
  src/ros/bag_check.cpp
  src/ros/bag_reader.cpp
  src/ros/compensator_ros.cpp
  src/ros/bag_writer.cpp
  src/ros/callback_thread.cpp
  src/ros/cpu_wakeup_latency.cpp)
# roslz4 and bz2: BagWriter compresses chunks itself, the bag check decompresses them as rosbag
# will (not exported by rosbag_storage).
target_link_libraries(${PROJECT_NAME}_ros ${PROJECT_NAME}_parameters ${PROJECT_NAME}_core ${catkin_LIBRARIES}
  yaml-cpp roslz4 bz2)
add_dependencies(${PROJECT_NAME}_ros ${PROJECT_NAME}_gencfg ${PROJECT_NAME}_generate_messages_cpp)

add_library(${PROJECT_NAME}_nodelet src/ros/compensator_nodelet.cpp)
target_link_libraries(${PROJECT_NAME}_nodelet ${PROJECT_NAME}_ros ${catkin_LIBRARIES})

add_executable(compensator_node src/ros/compensator_node.cpp)
target_link_libraries(compensator_node ${PROJECT_NAME}_ros ${catkin_LIBRARIES})

# Offline: the same core and conversions over a bag, no master.
add_executable(compensate_bag src/tools/compensate_bag.cpp)
target_link_libraries(compensate_bag ${PROJECT_NAME}_ros ${PROJECT_NAME}_tools ${catkin_LIBRARIES})

# The parameter section of docs/ros_api.md and the declarations of cfg/Compensator.cfg, from
# the parameter tables (`parameter_docs --update <repository>`; test_ros_conversions checks them).
add_executable(parameter_docs src/tools/parameter_docs.cpp)
target_link_libraries(parameter_docs ${PROJECT_NAME}_parameters ${catkin_LIBRARIES})

if(CATKIN_ENABLE_TESTING)
  find_package(rostest REQUIRED)
  find_package(roslaunch REQUIRED)
  roslaunch_add_file_check(launch/compensator.launch)
  roslaunch_add_file_check(launch/compensator.launch use_nodelet:=false)
  roslaunch_add_file_check(launch/playback.launch bag:=paper_bench.bag)
  roslaunch_add_file_check(launch/record.launch)

  # Test data: the paper bench scenario simulated at build time (simulate_imu, no master).
  set(PBC_TEST_DATA_DIR ${CATKIN_DEVEL_PREFIX}/share/${PROJECT_NAME}/test_data)
  set(PBC_BENCH_BAG ${PBC_TEST_DATA_DIR}/paper_bench.bag)
  add_custom_command(OUTPUT ${PBC_BENCH_BAG}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${PBC_TEST_DATA_DIR}
    COMMAND simulate_imu --scenario ${CMAKE_CURRENT_SOURCE_DIR}/config/scenarios/paper_bench.yaml
            --out ${PBC_BENCH_BAG}
    DEPENDS simulate_imu ${CMAKE_CURRENT_SOURCE_DIR}/config/scenarios/paper_bench.yaml
    COMMENT "Simulating config/scenarios/paper_bench.yaml for the ROS tests")
  add_custom_target(${PROJECT_NAME}_test_bags DEPENDS ${PBC_BENCH_BAG})

  # Bag regression, node and nodelet (through compensator.launch and playback.launch).
  add_executable(test_bag_accuracy EXCLUDE_FROM_ALL test/ros/bag_accuracy.cpp)
  target_link_libraries(test_bag_accuracy ${catkin_LIBRARIES} ${GTEST_LIBRARIES})
  add_dependencies(tests test_bag_accuracy ${PROJECT_NAME}_test_bags)
  add_rostest(test/ros/bag_node.test ARGS bag:=${PBC_BENCH_BAG}
    DEPENDENCIES test_bag_accuracy compensator_node ${PROJECT_NAME}_test_bags)
  add_rostest(test/ros/bag_nodelet_playback.test ARGS bag:=${PBC_BENCH_BAG}
    DEPENDENCIES test_bag_accuracy ${PROJECT_NAME}_nodelet ${PROJECT_NAME}_test_bags)

  # Crafted bad input on the real topic, checked on the outputs and /diagnostics.
  add_rostest_gtest(test_bad_input test/ros/bad_input.test test/ros/bad_input.cpp)
  target_link_libraries(test_bad_input ${catkin_LIBRARIES})
  add_dependencies(test_bad_input ${PROJECT_NAME}_generate_messages_cpp)
  add_rostest_gtest(test_input_sanity test/ros/input_sanity.test test/ros/input_sanity.cpp)
  target_link_libraries(test_input_sanity ${catkin_LIBRARIES})
  add_dependencies(test_input_sanity ${PROJECT_NAME}_generate_messages_cpp)

  # Invalid start-up parameters stop the node and the nodelet.
  add_rostest_gtest(test_bad_params test/ros/bad_params.test test/ros/bad_params.cpp)
  target_link_libraries(test_bad_params ${catkin_LIBRARIES})

  # dynamic_reconfigure (accepted and refused changes) and the calibration services.
  add_rostest_gtest(test_reconfigure test/ros/reconfigure.test test/ros/reconfigure.cpp)
  target_link_libraries(test_reconfigure ${catkin_LIBRARIES})
  add_dependencies(test_reconfigure ${PROJECT_NAME}_generate_messages_cpp ${PROJECT_NAME}_gencfg)

  # Conversions, parameter tables against config/compensator.yaml, cfg/Compensator.cfg and
  # docs/ros_api.md, and raw integration, no master.
  catkin_add_gtest(test_ros_conversions test/ros/conversions_test.cpp)
  target_link_libraries(test_ros_conversions ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
  add_dependencies(test_ros_conversions ${PROJECT_NAME}_gencfg)
  target_compile_definitions(test_ros_conversions PRIVATE PBC_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")

  # The bag writer's file, direct and ordinary writes, read back by rosbag (no master).
  catkin_add_gtest(test_bag_writer test/ros/bag_writer_test.cpp)
  target_link_libraries(test_bag_writer ${PROJECT_NAME}_ros ${catkin_LIBRARIES})

  # The bag reader against rosbag::View on bags rosbag wrote, and on cut or garbled ones (no master).
  # CallbackThread (the imu/data subscription's own thread), no master.
  catkin_add_gtest(test_callback_thread test/ros/callback_thread_test.cpp)
  target_link_libraries(test_callback_thread ${PROJECT_NAME}_ros ${catkin_LIBRARIES})

  catkin_add_gtest(test_bag_reader test/ros/bag_reader_test.cpp)
  target_link_libraries(test_bag_reader ${PROJECT_NAME}_ros ${catkin_LIBRARIES})

  # compensate_bag end to end on the bench bag, the batch runs of docs/batch.md, and its error
  # paths (no master).
  catkin_add_gtest(test_compensate_bag test/ros/compensate_bag_test.cpp)
  target_link_libraries(test_compensate_bag ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
  target_compile_definitions(test_compensate_bag PRIVATE
    PBC_COMPENSATE_BAG="$<TARGET_FILE:compensate_bag>"
    PBC_BENCH_BAG="${PBC_BENCH_BAG}"
    PBC_CATKIN_DEVEL="${CATKIN_DEVEL_PREFIX}"
    PBC_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")
  add_dependencies(test_compensate_bag compensate_bag ${PROJECT_NAME}_test_bags
    ${PROJECT_NAME}_generate_messages_cpp)

  # Reliability of the core (docs/reliability.md), no master: gains refused while data
  # flows, orientation lost, constant/noise input, Unix-time stamps, a 3 h run at 100 Hz
  # (PBC_LONG_RUN_HOURS=24 for the measured 24 h run).
  catkin_add_gtest(test_reliability test/ros/reliability_test.cpp)
  target_link_libraries(test_reliability ${PROJECT_NAME}_core ${PROJECT_NAME}_sim)
  target_compile_definitions(test_reliability PRIVATE
    PBC_SCENARIO_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config/scenarios")

  # Run-time faults while data flows, each seen in /diagnostics.
  add_rostest_gtest(test_faults test/ros/faults.test test/ros/faults.cpp)
  target_link_libraries(test_faults ${catkin_LIBRARIES})
  add_dependencies(test_faults ${PROJECT_NAME}_nodelet ${PROJECT_NAME}_generate_messages_cpp ${PROJECT_NAME}_gencfg)

  # The nodelet manager killed and respawned while data flows (compensator.launch respawn:=true).
  add_rostest_gtest(test_manager_restart test/ros/manager_restart.test test/ros/manager_restart.cpp)
  target_link_libraries(test_manager_restart ${catkin_LIBRARIES})
  add_dependencies(test_manager_restart ${PROJECT_NAME}_nodelet ${PROJECT_NAME}_generate_messages_cpp)
  # The same check on the stand-alone nodelet of compensator.launch (respawn:=true) killed.
  add_rostest(test/ros/manager_restart_standalone.test DEPENDENCIES test_manager_restart)

  # The nodelet unloaded and loaded again into a running manager while 1 kHz data flows.
  add_rostest_gtest(test_nodelet_unload test/ros/nodelet_unload.test test/ros/nodelet_unload.cpp)
  target_link_libraries(test_nodelet_unload ${catkin_LIBRARIES})
  add_dependencies(test_nodelet_unload ${PROJECT_NAME}_nodelet ${PROJECT_NAME}_generate_messages_cpp)
endif()
