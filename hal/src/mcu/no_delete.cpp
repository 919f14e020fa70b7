// The node image's classes with a virtual destructor (the HAL ports FrameSink / FrameSource and
// their implementations) get "deleting destructors" in their vtables, which reference operator
// delete; newlib's would pull in free() and _sbrk although nothing is ever allocated (there is
// no operator new in the image, and check_m4_image.cmake fails on malloc/free/_sbrk in the map).
// Deviation from the fw rules, on purpose: this file is NOT compiled with the fw prelude,
// because it must name `delete`. Both forms trap: reaching them is a bug.
#include <cstddef>

void operator delete(void* /*p*/) noexcept { __builtin_trap(); }
void operator delete(void* /*p*/, std::size_t /*n*/) noexcept { __builtin_trap(); }
