# Cross toolchain: Cortex-M4F bare metal (arm-none-eabi GCC 12, newlib-nano), hard float
# (single-precision FPU; double is done in software). The top-level CMakeLists sees
# CMAKE_SYSTEM_NAME "Generic" and builds only fw/ (with the node's MCU main loop), the hal codec
# and MCU backend (with its boards, hal/src/mcu/boards) and the images in toolchains/m4.
#   cmake -S . -B build-m4 -DCMAKE_TOOLCHAIN_FILE=toolchains/arm-none-eabi-m4.cmake
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR cortex-m4)
set(IMU_CROSS_TRIPLE arm-none-eabi)

set(CMAKE_C_COMPILER ${IMU_CROSS_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${IMU_CROSS_TRIPLE}-g++)
set(CMAKE_ASM_COMPILER ${IMU_CROSS_TRIPLE}-gcc)
set(CMAKE_OBJCOPY ${IMU_CROSS_TRIPLE}-objcopy CACHE FILEPATH "objcopy")
set(CMAKE_SIZE ${IMU_CROSS_TRIPLE}-size CACHE FILEPATH "size")

# Compiler checks link a test program: without a linker script and syscalls that fails, so only
# build a static library for them.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(IMU_M4_ARCH_FLAGS "-mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard -mthumb")
# No exceptions, RTTI or thread-safe statics anywhere on this target (fw/ adds the first two
# itself; repeating them is harmless). Sections per function so --gc-sections drops dead code.
set(CMAKE_C_FLAGS_INIT "${IMU_M4_ARCH_FLAGS} -ffunction-sections -fdata-sections")
set(CMAKE_CXX_FLAGS_INIT
    "${IMU_M4_ARCH_FLAGS} -ffunction-sections -fdata-sections -fno-exceptions -fno-rtti -fno-threadsafe-statics -fno-use-cxa-atexit")
set(CMAKE_ASM_FLAGS_INIT "${IMU_M4_ARCH_FLAGS}")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${IMU_M4_ARCH_FLAGS} --specs=nano.specs --specs=nosys.specs -Wl,--gc-sections")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
