# Post-build check of a bare-metal image: fails if the link map shows the heap (malloc, free,
# _sbrk or their reentrant _r forms), then records arm-none-eabi-size (Berkeley format) in
# <elf>.size and prints flash = text + data, RAM = data + bss (the stack section is in bss).
# Usage: cmake -DMAP=<map> -DELF=<elf> -DSIZE=<size tool> -DCHANNELS=<n>
#        [-DNM=<nm> -DREQUIRE_SYMBOL=<demangled name>] -P check_m4_image.cmake
file(READ ${MAP} map)
# A symbol or an input section named after a heap function: ".text._malloc_r", "(malloc)",
# " _sbrk". Identifier boundaries on both sides so that e.g. "freer" or "mallinfo" do not match.
string(REGEX MATCHALL "(^|[^A-Za-z0-9_])(_?malloc|_?free|_sbrk|_malloc_r|_free_r|_sbrk_r|_calloc_r|_realloc_r|calloc|realloc)([^A-Za-z0-9_]|$)"
       hits "${map}")
if(hits)
  list(REMOVE_DUPLICATES hits)
  message(FATAL_ERROR "${ELF}: link map ${MAP} references the heap: ${hits}")
endif()
execute_process(COMMAND ${SIZE} --format=berkeley ${ELF} OUTPUT_VARIABLE out RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${SIZE} failed on ${ELF}")
endif()
string(REGEX MATCH "\n[ \t]*([0-9]+)[ \t]+([0-9]+)[ \t]+([0-9]+)" row "${out}")
set(text ${CMAKE_MATCH_1})
set(data ${CMAKE_MATCH_2})
set(bss ${CMAKE_MATCH_3})
math(EXPR flash "${text} + ${data}")
math(EXPR ram "${data} + ${bss}")
set(summary "channels=${CHANNELS} text=${text} data=${data} bss=${bss} flash=${flash} ram=${ram}")
if(REQUIRE_SYMBOL)
  # The image must contain this (demangled) symbol, e.g. the real node's on_frame.
  execute_process(COMMAND ${NM} -C ${ELF} OUTPUT_VARIABLE syms RESULT_VARIABLE rc)
  string(FIND "${syms}" "${REQUIRE_SYMBOL}" at)
  if(NOT rc EQUAL 0 OR at EQUAL -1)
    message(FATAL_ERROR "${ELF}: symbol '${REQUIRE_SYMBOL}' not in the image (${NM} -C)")
  endif()
  string(SUBSTRING "${syms}" ${at} 200 tail)
  string(REGEX REPLACE "\n.*" "" line "${tail}")
  set(summary "${summary} symbol: ${line}")
endif()
file(WRITE ${ELF}.size "${out}${summary}\n")
message(STATUS "m4 image: ${summary} (no malloc/free/_sbrk in the map)")
