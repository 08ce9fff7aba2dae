# Offline tools that link the cores only (no ROS master, no bag).
add_executable(evaluate_compensator src/tools/evaluate_compensator.cpp)
target_link_libraries(evaluate_compensator ${PROJECT_NAME}_core ${PROJECT_NAME}_sim)
