# Compiler checks for mgn's own targets (core, mgn-cli, the C++ tests, the Python extension);
# never for third-party code, whose headers come in as system includes (-isystem).
#   MGN_WARNINGS_AS_ERRORS  OFF (default) or ON: -Werror on top of -Wall -Wextra (GCC, Clang).
#   MGN_SANITIZE            empty (default) or a -fsanitize= list, e.g. "address,undefined":
#                           compile and link flags, with frame pointers kept and undefined
#                           behaviour fatal (-fno-sanitize-recover=undefined).
include_guard(GLOBAL)

option(MGN_WARNINGS_AS_ERRORS "Treat compiler warnings in mgn's own code as errors (-Werror)" OFF)
set(MGN_SANITIZE "" CACHE STRING
    "Sanitizers for mgn's own targets (-fsanitize= list, e.g. address,undefined); empty: none")

if(MGN_SANITIZE AND NOT CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
  message(FATAL_ERROR "MGN_SANITIZE=${MGN_SANITIZE} needs GCC or Clang, not ${CMAKE_CXX_COMPILER_ID}")
endif()

# mgn_compile_checks(<target>): -Wall -Wextra, -Werror and the sanitizer flags for one mgn target.
function(mgn_compile_checks target)
  target_compile_options(${target} PRIVATE $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra>)
  if(MGN_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE $<$<CXX_COMPILER_ID:GNU,Clang>:-Werror>)
  endif()
  if(MGN_SANITIZE)
    set(_flags -fsanitize=${MGN_SANITIZE} -fno-omit-frame-pointer)
    if(MGN_SANITIZE MATCHES "undefined")
      list(APPEND _flags -fno-sanitize-recover=undefined)
    endif()
    target_compile_options(${target} PRIVATE ${_flags})
    target_link_options(${target} PRIVATE -fsanitize=${MGN_SANITIZE})
  endif()
endfunction()
