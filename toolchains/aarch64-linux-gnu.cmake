# Cross toolchain: aarch64 Linux co-processor (Debian's g++-aarch64-linux-gnu, multiarch arm64
# libraries for gtest, benchmark and libgpiod). Builds the whole project; tests run under
# qemu-aarch64 user mode through CMAKE_CROSSCOMPILING_EMULATOR (ctest and gtest_discover_tests).
#   cmake -S . -B build-aarch64 -DCMAKE_TOOLCHAIN_FILE=toolchains/aarch64-linux-gnu.cmake
# Arm64 libraries: dpkg --add-architecture arm64 && apt-get update &&
#   apt-get install libgtest-dev:arm64 libbenchmark-dev:arm64 libgpiod-dev:arm64
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(IMU_CROSS_TRIPLE aarch64-linux-gnu)

set(CMAKE_C_COMPILER ${IMU_CROSS_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${IMU_CROSS_TRIPLE}-g++)

# Debian multiarch: arm64 headers live in /usr/include (shared) and /usr/include/aarch64-linux-gnu,
# libraries and CMake package files in /usr/lib/aarch64-linux-gnu. The cross compiler already
# searches those; CMake must look in /usr with the multiarch library architecture and must never
# pick a host (x86_64) library.
set(CMAKE_LIBRARY_ARCHITECTURE ${IMU_CROSS_TRIPLE})
set(CMAKE_FIND_ROOT_PATH /usr/${IMU_CROSS_TRIPLE} /usr)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/${IMU_CROSS_TRIPLE}/pkgconfig:/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# Run target executables (tests, gtest discovery) in qemu user mode with the cross sysroot.
find_program(IMU_QEMU_AARCH64 qemu-aarch64)
if(IMU_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR "${IMU_QEMU_AARCH64};-L;/usr/${IMU_CROSS_TRIPLE}")
endif()
