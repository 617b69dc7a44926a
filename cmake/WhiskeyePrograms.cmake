# whiskeye_program(TARGET): a product executable (daemon or tool). Built into build/bin so scripts
# and users find every program in one place, and installed to bin/.
function(whiskeye_program target)
  set_target_properties(${target} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/bin)
  install(TARGETS ${target} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endfunction()
