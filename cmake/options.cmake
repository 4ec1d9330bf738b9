# Build options applied to polrig's own targets only (never to the third-party libraries):
# polrig_options carries the warnings, POLRIG_WERROR and POLRIG_SANITIZERS. Link it PRIVATE.

if(POLRIG_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "POLRIG_FUZZ=ON needs clang (libFuzzer), but the C++ compiler is "
            "${CMAKE_CXX_COMPILER_ID} (${CMAKE_CXX_COMPILER}). Configure a fresh build folder with "
            "-DCMAKE_CXX_COMPILER=clang++ (Debian: apt-get install clang libclang-rt-14-dev).")
  endif()
  if(POLRIG_SANITIZERS STREQUAL "")
    # A fuzzer without AddressSanitizer finds only crashes; leaks and overflows need it.
    set(POLRIG_SANITIZERS "address;undefined" CACHE STRING
        "Sanitizers for polrig's own targets, a list such as 'address;undefined' (empty: none)" FORCE)
    message(STATUS "POLRIG_FUZZ: POLRIG_SANITIZERS set to address;undefined")
  endif()
endif()

add_library(polrig_options INTERFACE)
target_compile_options(polrig_options INTERFACE
  -Wall -Wextra -Wpedantic -Wno-missing-field-initializers
  $<$<BOOL:${POLRIG_WERROR}>:-Werror>)

if(NOT POLRIG_SANITIZERS STREQUAL "")
  set(_known address undefined leak thread)
  foreach(s IN LISTS POLRIG_SANITIZERS)
    if(NOT s IN_LIST _known)
      message(FATAL_ERROR "POLRIG_SANITIZERS: unknown sanitizer '${s}' (expected a list of: ${_known})")
    endif()
  endforeach()
  list(JOIN POLRIG_SANITIZERS "," _list)
  # Every finding stops the program (a non-zero exit), so a test cannot pass over one.
  set(_flags -fsanitize=${_list} -fno-sanitize-recover=all -fno-omit-frame-pointer)
  target_compile_options(polrig_options INTERFACE ${_flags})
  target_link_options(polrig_options INTERFACE ${_flags})
  message(STATUS "polrig: sanitizers ${_list}")
endif()
