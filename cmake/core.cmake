# Estimation core: no ROS include, its own library, tested without a master.
include(${CMAKE_CURRENT_LIST_DIR}/core_sources.cmake)
add_library(${PROJECT_NAME}_core ${PBC_CORE_SOURCES})
target_include_directories(${PROJECT_NAME}_core PUBLIC include)
# FrequencyTracker plans its transform on a thread of its own.
find_package(Threads REQUIRED)
target_link_libraries(${PROJECT_NAME}_core PUBLIC Eigen3::Eigen PkgConfig::FFTW3 yaml-cpp Threads::Threads)
# The headers most of its files include, parsed once for the library instead of once per file.
target_precompile_headers(${PROJECT_NAME}_core PRIVATE <algorithm> <array> <cmath> <vector> <Eigen/Dense>)

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(test_core
    test/core/main.cpp
    test/core/test_frequency_tracker.cpp
    test/core/test_compensator.cpp
    test/core/test_parameter_table.cpp
    test/core/test_bad_input.cpp
    test/core/test_gain_tuning.cpp
    test/core/test_gyro_attitude.cpp
    test/core/test_heave_filter.cpp
    test/core/test_lever_arm.cpp
    test/core/test_time_base.cpp
    test/core/test_wiener_heave.cpp
    test/core/test_toeplitz.cpp
    test/core/test_noise_floor.cpp
    test/core/test_broadband_wave.cpp
    test/core/test_wave_consistency.cpp
    test/core/test_harmonic_model.cpp
    test/core/test_paper_loop.cpp
    test/core/test_leveller.cpp
    test/core/test_turn_detector.cpp
    test/core/test_calibration_window.cpp
    test/core/test_drift_observer.cpp
    test/core/test_frequency_drift.cpp
    test/core/test_periodic_wave.cpp
    test/core/test_numeric.cpp
    test/core/test_work_thread.cpp
    test/core/test_background.cpp
    test/core/test_raw_integrator.cpp
    test/core/test_real_world_streams.cpp)
  target_link_libraries(test_core ${PROJECT_NAME}_core)
  # Every test file includes GoogleTest, most the compensator: parsed once for the executable.
  target_precompile_headers(test_core PRIVATE <gtest/gtest.h> <cmath> <random> <vector> <Eigen/Dense>
                            "${CMAKE_CURRENT_SOURCE_DIR}/include/periodic_bias_compensation/core/compensator.h")
  # test_real_world_streams reads ../shared/data beside the repository when it is there.
  target_compile_definitions(test_core PRIVATE PBC_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")
endif()
