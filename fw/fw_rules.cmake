# imu_apply_fw_rules(<target> [SYMBOL_TEST <test name>]): the firmware rules, in one place, for
# every target whose code runs on the co-processor (fw/, the node and its MCU main loop, the hal
# codec, the hal MCU backend and its boards, the M4 images):
#  * -fno-exceptions -fno-rtti;
#  * -ffp-contract=off: no fused multiply-add contraction, so float/double results are the same
#    bits on every target (the Cortex-M4's VFMA.F32 and aarch64's FMADD would otherwise round
#    differently from x86-64; the M4 node image's telemetry is compared with the host's byte
#    for byte). Cost: a separate multiply and add where one fused instruction would do;
#  * -fno-math-errno: fw has no errno to read (no OS), so a math function need not set it:
#    sqrt(f) compiles to the FPU's own instruction (VSQRT.F32 on the M4, SQRTSS on x86-64;
#    both correctly rounded, like the library's) instead of a call that checks its argument.
#    It changes no result;
#  * fw/src/fw_prelude.hpp force-included in every translation unit: it includes the only
#    standard headers fw code may use and then poisons heap, exception, RTTI, stdio and OS
#    identifiers (a use is a compile error);
#  * the project's strict warnings (imu_warnings);
#  * for a static library in a build with tests (not bare metal): a ctest that runs
#    `nm --undefined-only` on the archive and fails on malloc/free/new/delete, exception,
#    RTTI and stdio symbols (fw/check_fw_symbols.cmake), i.e. on what the compiler generates.
#    Its name is SYMBOL_TEST, default <target>_no_heap_symbols. (The M4 image has its own
#    check on the link map: toolchains/m4/check_m4_image.cmake.)
set(IMU_FW_PRELUDE ${CMAKE_CURRENT_LIST_DIR}/src/fw_prelude.hpp)
set(IMU_FW_SYMBOL_CHECK ${CMAKE_CURRENT_LIST_DIR}/check_fw_symbols.cmake)

function(imu_apply_fw_rules target)
  cmake_parse_arguments(ARG "" "SYMBOL_TEST" "" ${ARGN})
  target_compile_options(${target} PRIVATE -fno-exceptions -fno-rtti -ffp-contract=off
    -fno-math-errno "SHELL:-include ${IMU_FW_PRELUDE}")
  target_link_libraries(${target} PRIVATE imu_warnings)
  get_target_property(type ${target} TYPE)
  if(type STREQUAL "STATIC_LIBRARY" AND NOT IMU_BARE_METAL)
    if(NOT ARG_SYMBOL_TEST)
      set(ARG_SYMBOL_TEST ${target}_no_heap_symbols)
    endif()
    add_test(NAME ${ARG_SYMBOL_TEST}
      COMMAND ${CMAKE_COMMAND} -DNM=${CMAKE_NM} -DLIB=$<TARGET_FILE:${target}>
              -P ${IMU_FW_SYMBOL_CHECK})
    set_tests_properties(${ARG_SYMBOL_TEST} PROPERTIES LABELS unit)
  endif()
endfunction()
