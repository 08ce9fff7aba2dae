# Fuzz harnesses (test/fuzz/, docs/reliability.md). libFuzzer builds them with clang in a
# separate build (scripts/fuzz). Here, in the ordinary catkin build, each harness is linked to a
# gtest that replays its committed corpus (test/fuzz/corpus/<target>/): seeds and every input
# that once found a bug run in scripts/test, also under ASan+UBSan (PBC_SANITIZE=ON).
if(CATKIN_ENABLE_TESTING)
  set(PBC_FUZZ_TARGETS compensator scenario imu_msg params bag csv)
  foreach(target ${PBC_FUZZ_TARGETS})
    catkin_add_gtest(test_fuzz_corpus_${target} test/fuzz/replay_main.cpp test/fuzz/fuzz_${target}.cpp)
    target_compile_definitions(test_fuzz_corpus_${target} PRIVATE
      PBC_FUZZ_CORPUS="${CMAKE_CURRENT_SOURCE_DIR}/test/fuzz/corpus/${target}")
  endforeach()
  target_link_libraries(test_fuzz_corpus_compensator ${PROJECT_NAME}_core)
  target_link_libraries(test_fuzz_corpus_scenario ${PROJECT_NAME}_sim)
  target_link_libraries(test_fuzz_corpus_csv ${PROJECT_NAME}_gap)
  foreach(target imu_msg params bag)
    target_link_libraries(test_fuzz_corpus_${target} ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
    add_dependencies(test_fuzz_corpus_${target} ${PROJECT_NAME}_generate_messages_cpp)
  endforeach()
  # bag: src/tools/compensate_bag.cpp is compiled in.
  target_link_libraries(test_fuzz_corpus_bag ${PROJECT_NAME}_tools)
endif()
