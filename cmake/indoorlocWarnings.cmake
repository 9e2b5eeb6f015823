# Warning flags and optional sanitizers, applied per target through indoorloc_set_warnings().
function(indoorloc_set_warnings target)
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                           -Wno-sign-conversion)
  endif()
endfunction()

if(INDOORLOC_NATIVE)
  add_compile_options(-march=native)
endif()

if(INDOORLOC_SANITIZE)
  # Applied to everything built in this tree (library and tests) so that instrumented and
  # uninstrumented code never mix inside one binary.
  add_compile_options(-fsanitize=${INDOORLOC_SANITIZE} -fno-omit-frame-pointer
                      -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${INDOORLOC_SANITIZE})
endif()
