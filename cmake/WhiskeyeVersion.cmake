# Script (cmake -P), run at every build: writes the version every program's --version prints.
#   -DSOURCE_DIR=<source tree> -DVERSION=<project version> -DTEMPLATE=<version.cpp.in> -DOUTPUT=<file>
# The text is the project version, followed by `git describe --always --dirty` of the source tree in
# brackets when the tree is a git checkout of its own ("0.1.0 (0358d50-dirty)"); from a source
# tarball, even one unpacked inside another repository, the project version alone. configure_file
# rewrites OUTPUT only when the text changed, so an unchanged tree recompiles nothing.
set(WHISKEYE_VERSION_TEXT "${VERSION}")
find_program(WHISKEYE_GIT git)
if(WHISKEYE_GIT AND EXISTS "${SOURCE_DIR}/.git")
  execute_process(COMMAND "${WHISKEYE_GIT}" -C "${SOURCE_DIR}" describe --always --dirty
                  OUTPUT_VARIABLE describe RESULT_VARIABLE status ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(status EQUAL 0 AND NOT describe STREQUAL "")
    set(WHISKEYE_VERSION_TEXT "${VERSION} (${describe})")
  endif()
endif()
configure_file("${TEMPLATE}" "${OUTPUT}" @ONLY)
