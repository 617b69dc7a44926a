# Runs lcm-gen for one language over all .lcm files and fails unless every expected output was
# written anew. lcm-gen exits 0 on some bad input (e.g. an unknown flag prints usage), so its exit
# status alone cannot be trusted.
# Inputs: LCM_GEN, FLAGS (;-list), OUT_DIR, INPUTS (;-list), EXPECTED (;-list of files)
# For C++ headers, message constants are made `static constexpr` (implicitly inline since C++17):
# lcm-gen 1.3.1 declares them `static const` without a definition, so any ODR-use (binding to a
# const&, as gtest's EXPECT_EQ does at -O0) fails to link.
file(REMOVE_RECURSE "${OUT_DIR}")
file(MAKE_DIRECTORY "${OUT_DIR}")
execute_process(COMMAND "${LCM_GEN}" ${FLAGS} ${INPUTS}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "lcm-gen failed (exit ${rc}):\n${out}${err}")
endif()
foreach(f ${EXPECTED})
  if(NOT EXISTS "${f}")
    message(FATAL_ERROR "lcm-gen did not write ${f}:\n${out}${err}")
  endif()
endforeach()

foreach(f ${EXPECTED})
  if(f MATCHES "\\.hpp$")
    file(READ "${f}" text)
    string(REGEX REPLACE "static const ([a-z0-9_]+)( +[A-Za-z0-9_]+ = )" "static constexpr \\1\\2" text "${text}")
    file(WRITE "${f}" "${text}")
  endif()
endforeach()
