// Force-included (compiler flag -include) at the top of every fw/ translation unit.
// It includes every standard header fw/ may use, then poisons the identifiers fw/ must never
// use. A later use of a poisoned name is a compile error, which is the proof that fw/ has no
// heap, no exceptions, no RTTI, no stdio/iostream and no OS calls. `delete` is not poisoned
// because `= delete` declarations are wanted; operator delete is caught by the symbol check.
#ifndef IMU_FW_PRELUDE_HPP
#define IMU_FW_PRELUDE_HPP

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>
#include <utility>

#if defined(__EXCEPTIONS) || defined(__cpp_exceptions)
#error "fw/ must be compiled with -fno-exceptions"
#endif
#if defined(__GXX_RTTI) || defined(__cpp_rtti)
#error "fw/ must be compiled with -fno-rtti"
#endif

// NOLINTBEGIN
#pragma GCC poison malloc calloc realloc free aligned_alloc posix_memalign strdup new
#pragma GCC poison throw try catch typeid dynamic_cast
#pragma GCC poison printf fprintf sprintf snprintf puts fopen fclose fread fwrite cout cerr cin
#pragma GCC poison getenv system exit abort sleep usleep nanosleep clock_gettime gettimeofday
#pragma GCC poison socket ioctl mmap pthread_create
// NOLINTEND

#endif  // IMU_FW_PRELUDE_HPP
