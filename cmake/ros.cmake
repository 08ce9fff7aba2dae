# ROS wrapper, nodelet, node, offline bag tools and rostests.
include_directories(include ${catkin_INCLUDE_DIRS})

# Wrapper library: message conversions, parameters, the CompensatorRos class.
add_library(${PROJECT_NAME}_ros
  src/ros/conversions.cpp
  src/ros/parameters.cpp
  src/ros/raw_integrator.cpp
  src/ros/compensator_ros.cpp)
target_link_libraries(${PROJECT_NAME}_ros ${PROJECT_NAME}_core ${catkin_LIBRARIES} yaml-cpp)
add_dependencies(${PROJECT_NAME}_ros ${PROJECT_NAME}_gencfg ${PROJECT_NAME}_generate_messages_cpp)

add_library(${PROJECT_NAME}_nodelet src/ros/compensator_nodelet.cpp)
target_link_libraries(${PROJECT_NAME}_nodelet ${PROJECT_NAME}_ros ${catkin_LIBRARIES})

add_executable(compensator_node src/ros/compensator_node.cpp)
target_link_libraries(compensator_node ${PROJECT_NAME}_ros ${catkin_LIBRARIES})

# Offline: the same core and conversions over a bag, no master.
add_executable(compensate_bag src/tools/compensate_bag.cpp)
target_link_libraries(compensate_bag ${PROJECT_NAME}_ros ${catkin_LIBRARIES})

install(TARGETS ${PROJECT_NAME}_ros ${PROJECT_NAME}_nodelet compensator_node compensate_bag
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(DIRECTORY include/${PROJECT_NAME}/ros DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION})
install(FILES nodelet_plugins.xml DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})
