# Every third-party dependency, found once for the whole tree. All come from Debian 12 packages
# installed by scripts/install-deps.
find_package(PkgConfig REQUIRED)
# Debian's LCM 1.3.1 ships no CMake package; pkg-config's lcm.pc needs glib-2.0 (libglib2.0-dev).
pkg_check_modules(LCM REQUIRED IMPORTED_TARGET lcm)
find_program(LCM_GEN_EXECUTABLE lcm-gen REQUIRED)
if(WHISKEYE_JAVA)
  find_file(LCM_JAR lcm.jar PATHS /usr/share/java REQUIRED NO_DEFAULT_PATH)
  find_package(Java 11 REQUIRED COMPONENTS Development)
endif()
# sd_notify for the daemons (libsystemd-dev) and the GPIO lines of whiskerd (libgpiod-dev's C++ binding).
pkg_check_modules(SYSTEMD REQUIRED IMPORTED_TARGET libsystemd)
pkg_check_modules(GPIODCXX REQUIRED IMPORTED_TARGET libgpiodcxx)

find_package(Threads REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(OpenCVParts REQUIRED)  # OpenCV::core, OpenCV::imgproc, OpenCV::imgcodecs
# libjpeg directly for slamd's MJPEG frames, to see its warnings (a damaged frame) that OpenCV hides.
find_package(JPEG REQUIRED)  # libjpeg-dev (libjpeg62-turbo)
# libturbojpeg (libturbojpeg0-dev): the known MJPEG frames of camerad's tests (tests/support) and the
# decode benchmark's comparison.
pkg_check_modules(TURBOJPEG REQUIRED IMPORTED_TARGET libturbojpeg)
find_package(yaml-cpp REQUIRED)
find_package(CLI11 REQUIRED)
find_package(nlohmann_json 3 REQUIRED)  # vita-eval JSON output (nlohmann-json3-dev)
if(WHISKEYE_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
find_package(Python3 REQUIRED COMPONENTS Interpreter)
if(WHISKEYE_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()
