# What `catkin_make install` puts in place: libraries, executables, headers, the nodelet's plugin
# description, launch files, configurations, scenarios and the rviz view.
install(TARGETS
    ${PROJECT_NAME}_core ${PROJECT_NAME}_sim ${PROJECT_NAME}_sim_ros ${PROJECT_NAME}_parameters ${PROJECT_NAME}_ros
    ${PROJECT_NAME}_nodelet ${PROJECT_NAME}_gap ${PROJECT_NAME}_tools ${PROJECT_NAME}_metrics
    compensator_node compensate_bag simulate_imu simulator_node diagnose_gap validate_gap
    evaluate_compensator parameter_docs
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(DIRECTORY include/${PROJECT_NAME}/ DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION})
install(FILES nodelet_plugins.xml DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})
install(DIRECTORY launch config rviz DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})
