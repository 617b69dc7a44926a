# whiskeye_add_gtest(NAME LABEL <unit|integration|vm> SOURCES ... [LIBS ...] [TIMEOUT s] [NETNS]
#                    [SERIAL_WITH_VM] [THREADS])
# THREADS: the binary tests code that hands data between threads; its tests also carry the label
# `threads`, which scripts/test runs under ThreadSanitizer.
# One gtest binary, each TEST discovered as its own ctest test and labelled, so
# `ctest -L unit` runs the fast suite and the sanitizer build can build only what it runs.
include(GoogleTest)

function(whiskeye_add_gtest name)
  cmake_parse_arguments(ARG "NETNS;SERIAL_WITH_VM;THREADS" "LABEL;TIMEOUT" "SOURCES;LIBS" ${ARGN})
  if(NOT ARG_LABEL)
    message(FATAL_ERROR "whiskeye_add_gtest(${name}): LABEL is required")
  endif()
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  add_executable(${name} ${ARG_SOURCES})
  if(ARG_NETNS)
    # Tests that use udpm:// run (and are discovered) inside a private network namespace.
    set_target_properties(${name} PROPERTIES CROSSCOMPILING_EMULATOR ${PROJECT_SOURCE_DIR}/scripts/netns-run)
  endif()
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gmock GTest::gtest_main)
  set(extra)
  if(ARG_SERIAL_WITH_VM)
    # Tests that hold a real-time property (periods, deadlines, keep-alive gaps) do not run beside a
    # TCG guest, which takes a whole core of the 2-core runner (tests/vm: RESOURCE_LOCK qemu_vm).
    set(extra RESOURCE_LOCK qemu_vm)
  endif()
  gtest_discover_tests(${name}
    PROPERTIES LABELS ${ARG_LABEL} TIMEOUT ${ARG_TIMEOUT} ${extra}
    DISCOVERY_TIMEOUT 60)
  if(ARG_THREADS)
    # A second label cannot go through gtest_discover_tests' PROPERTIES (the list is split into
    # keys), so a script ctest reads after the discovered tests (${name}_TESTS) sets both.
    set(script "${CMAKE_CURRENT_BINARY_DIR}/${name}_threads_label.cmake")
    file(WRITE "${script}"
         "if(${name}_TESTS)\n"
         "  set_tests_properties(\${${name}_TESTS} PROPERTIES LABELS \"${ARG_LABEL};threads\")\n"
         "endif()\n")
    set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${script}")
    set_property(GLOBAL APPEND PROPERTY WHISKEYE_TESTS_threads ${name})
  endif()
  set_property(GLOBAL APPEND PROPERTY WHISKEYE_TESTS_${ARG_LABEL} ${name})
endfunction()

# Targets `tests_unit`, `tests_integration`, `tests_vm`, `tests_threads`: build just the binaries of
# one label.
function(whiskeye_finish_test_targets)
  foreach(label unit integration vm threads)
    get_property(targets GLOBAL PROPERTY WHISKEYE_TESTS_${label})
    add_custom_target(tests_${label})
    if(targets)
      add_dependencies(tests_${label} ${targets})
    endif()
  endforeach()
endfunction()
