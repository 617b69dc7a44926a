# Runs at install time (cmake --install, cpack), not at configure time: the units name absolute paths
# (ExecStart=, EnvironmentFile=, --config) that depend on the prefix chosen then, e.g.
# `cmake --install build --prefix /usr`. <sysconfdir> follows GNUInstallDirs: /etc for the /usr
# prefix, <prefix>/etc otherwise. Inputs (set by systemd/CMakeLists.txt): WHISKEYE_SYSTEMD_SRC,
# WHISKEYE_SYSTEMD_STAGE, WHISKEYE_SYSTEMD_UNITDIR (relative to the prefix), WHISKEYE_UNITS,
# WHISKEYE_CONFIG_FILES.
set(prefix "${CMAKE_INSTALL_PREFIX}")
if(prefix STREQUAL "/usr")
  set(sysconfdir /etc)
else()
  set(sysconfdir "${prefix}/etc")
endif()
set(WHISKEYE_BINDIR "${prefix}/bin")
set(WHISKEYE_CONFDIR "${sysconfdir}/whiskeye")
set(WHISKEYE_ENVFILE "${sysconfdir}/default/whiskeye")
set(WHISKEYE_DOCDIR "${prefix}/share/doc/whiskeye")
# On the robot Debian has /usr/sbin/ip (iproute2), whatever the build host resolves.
set(WHISKEYE_IP /usr/sbin/ip)

set(stage "${WHISKEYE_SYSTEMD_STAGE}")
file(REMOVE_RECURSE "${stage}")
set(units)
foreach(unit ${WHISKEYE_UNITS})
  configure_file("${WHISKEYE_SYSTEMD_SRC}/${unit}.in" "${stage}/${unit}" @ONLY)
  list(APPEND units "${stage}/${unit}")
endforeach()
configure_file("${WHISKEYE_SYSTEMD_SRC}/60-whiskeye-lcm.sysctl" "${stage}/60-whiskeye-lcm.conf" @ONLY)
configure_file("${WHISKEYE_SYSTEMD_SRC}/whiskeye.sysusers" "${stage}/whiskeye.conf" COPYONLY)
configure_file("${WHISKEYE_SYSTEMD_SRC}/whiskeye.env" "${stage}/whiskeye" COPYONLY)

file(INSTALL ${units} DESTINATION "${prefix}/${WHISKEYE_SYSTEMD_UNITDIR}")
file(INSTALL "${stage}/whiskeye.conf" DESTINATION "${prefix}/lib/sysusers.d")
file(INSTALL "${stage}/60-whiskeye-lcm.conf" DESTINATION "${prefix}/lib/sysctl.d")
file(INSTALL "${WHISKEYE_SYSTEMD_SRC}/60-whiskeye-gpio.rules" DESTINATION "${prefix}/lib/udev/rules.d")
file(INSTALL "${stage}/whiskeye" DESTINATION "${sysconfdir}/default")
file(INSTALL ${WHISKEYE_CONFIG_FILES} DESTINATION "${WHISKEYE_CONFDIR}")
