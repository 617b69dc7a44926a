# Assembles the whiskeye Python package (python/CMakeLists.txt): copies lcm-gen's modules and our
# sources into PKG, writes channels.py from channels.h, and makes `import whiskeye` bring in
# whiskeye.log and whiskeye.channels too.
# Inputs: PKG, GENERATED_DIR, SOURCES (;-list), CHANNELS_H, TYPES (;-list of LCM type names)
cmake_minimum_required(VERSION 3.22)  # IN_LIST and the policies of the project
file(REMOVE_RECURSE "${PKG}")
file(MAKE_DIRECTORY "${PKG}")
file(GLOB generated "${GENERATED_DIR}/*.py")
file(COPY ${generated} ${SOURCES} DESTINATION "${PKG}")

# channels.h: `inline constexpr const char* kName = "CHANNEL";` and `{kName, "type_t"},` entries.
file(READ "${CHANNELS_H}" text)
# (Matched without the closing ';', which is CMake's list separator.)
string(REGEX MATCHALL "inline constexpr const char\\* k[A-Za-z0-9]+ = \"[A-Z0-9_]+\"" names "${text}")
string(REGEX MATCHALL "{k[A-Za-z0-9]+, \"[a-z0-9_]+\"}" entries "${text}")
if(NOT names OR NOT entries)
  message(FATAL_ERROR "${CHANNELS_H}: no channel names or no kChannelTypes entries found")
endif()
set(py_names "")
set(py_types "")
foreach(n ${names})
  string(REGEX REPLACE ".*\\* (k[A-Za-z0-9]+) = \"([A-Z0-9_]+)\"" "\\1" constant "${n}")
  string(REGEX REPLACE ".*\\* (k[A-Za-z0-9]+) = \"([A-Z0-9_]+)\"" "\\2" channel "${n}")
  set(channel_of_${constant} ${channel})
  string(APPEND py_names "${channel} = \"${channel}\"\n")
  set(type_of_${channel} "")
endforeach()
foreach(e ${entries})
  string(REGEX REPLACE "{(k[A-Za-z0-9]+), \"([a-z0-9_]+)\"}" "\\1" constant "${e}")
  string(REGEX REPLACE "{(k[A-Za-z0-9]+), \"([a-z0-9_]+)\"}" "\\2" type "${e}")
  if(NOT DEFINED channel_of_${constant})
    message(FATAL_ERROR "${CHANNELS_H}: kChannelTypes names ${constant}, which is no channel constant")
  endif()
  if(NOT type IN_LIST TYPES)
    message(FATAL_ERROR "${CHANNELS_H}: ${constant} is given type ${type}, which no lcmtypes/*.lcm defines")
  endif()
  set(type_of_${channel_of_${constant}} ${type})
  string(APPEND py_types "    ${channel_of_${constant}}: \"${type}\",\n")
endforeach()
foreach(n ${names})
  string(REGEX REPLACE ".*\\* (k[A-Za-z0-9]+) = \"([A-Z0-9_]+)\"" "\\2" channel "${n}")
  if(type_of_${channel} STREQUAL "")
    message(FATAL_ERROR "${CHANNELS_H}: channel ${channel} has no entry in kChannelTypes")
  endif()
endforeach()
file(WRITE "${PKG}/channels.py" "\"\"\"The stack's LCM channel names and the type each carries (docs/lcm-channels.md).

Generated at build time from common/include/whiskeye/common/channels.h, the one home of the names
(python/assemble.cmake): do not edit; change channels.h. python/whiskeye/channels.py is this file
checked in, so that the source tree's package imports too; test python.LogReaderChannelsAndTypes
fails until it is copied again from build/python/whiskeye/channels.py.
\"\"\"

${py_names}
# Channel -> name of the LCM type (a module and class of this package) it carries.
TYPES = {
${py_types}}
")

file(APPEND "${PKG}/__init__.py" "
# Added by the build (python/assemble.cmake): the channel names and the log reader.
from . import channels, log
")
