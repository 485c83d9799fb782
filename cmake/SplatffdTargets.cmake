# Shared compile settings for every SplatFFD target: strict warnings, native vector width, sanitizers.
function(sffd_target_defaults target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wcast-align
      -Woverloaded-virtual -Wdouble-promotion -Wimplicit-fallthrough
      -Werror=return-type -Werror=uninitialized>)
  if(SFFD_NATIVE)
    target_compile_options(${target} PRIVATE -march=native)
  endif()
  if(SFFD_SANITIZE)
    target_compile_options(${target} PUBLIC -fsanitize=address,undefined -fno-omit-frame-pointer
      -fno-sanitize-recover=undefined)
    target_link_options(${target} PUBLIC -fsanitize=address,undefined)
  endif()
endfunction()

# sffd_library(name SOURCES ... DEPS ...): a static library for one runtime part or one system.
function(sffd_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS})
  sffd_target_defaults(${name})
endfunction()
