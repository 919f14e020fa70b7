# Fails if the fw static library references a heap, exception, RTTI or stdio symbol.
execute_process(COMMAND ${NM} --undefined-only ${LIB} OUTPUT_VARIABLE syms RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "nm failed on ${LIB}")
endif()
set(forbidden
  "malloc" "calloc" "realloc" "free" "_Znwm" "_Znam" "_Znwj" "_Znaj" "_ZdlPv" "_ZdaPv"
  "__cxa_throw" "__cxa_allocate_exception" "__cxa_begin_catch" "__gxx_personality_v0"
  "__dynamic_cast" "printf" "puts" "fopen" "fwrite" "_ZSt4cout" "_ZSt4cerr" "_sbrk"
  "_Unwind_Resume")
set(bad "")
string(REPLACE "\n" ";" lines "${syms}")
foreach(line IN LISTS lines)
  string(REGEX MATCH "[^ ]+$" sym "${line}")
  foreach(f IN LISTS forbidden)
    if(sym STREQUAL f)
      list(APPEND bad "${sym}")
    endif()
  endforeach()
  if(sym MATCHES "^_ZTI")  # typeinfo: RTTI
    list(APPEND bad "${sym}")
  endif()
endforeach()
if(bad)
  message(FATAL_ERROR "fw library references forbidden symbols: ${bad}")
endif()
message(STATUS "fw library: no heap/exception/RTTI/stdio symbols")
