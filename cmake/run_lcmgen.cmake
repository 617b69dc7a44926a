# Runs lcm-gen for one language over all .lcm files and fails unless every expected output was
# written anew. lcm-gen exits 0 on some bad input (e.g. an unknown flag prints usage), so its exit
# status alone cannot be trusted.
# Inputs: LCM_GEN, FLAGS (;-list), OUT_DIR, INPUTS (;-list), EXPECTED (;-list of files)
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
