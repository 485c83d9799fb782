# Shared compile settings for every SplatFFD target: strict warnings, sanitizers, -march=native when
# SFFD_NATIVE asks for it.
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
    # GCC's flow analysis sees through the sanitizers' instrumentation into libstdc++ (std::regex's
    # std::function state) and reports maybe-uninitialized reads the release build does not: keep them
    # as warnings there so the sanitizer build does not fail on the standard library's code.
    target_compile_options(${target} PRIVATE $<$<CXX_COMPILER_ID:GNU>:-Wno-error=maybe-uninitialized>)
    target_link_options(${target} PUBLIC -fsanitize=address,undefined)
  endif()
  set_property(GLOBAL APPEND PROPERTY SFFD_TARGETS ${target})
endfunction()

# sffd_library(name SOURCES ... DEPS ...): a static library for one runtime part or one system.
function(sffd_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS})
  sffd_target_defaults(${name})
endfunction()

# sffd_header_library(name DIR folder DEPS ...): a header-only part (the ECS); DIR is the folder whose
# headers it owns, for the include-boundary check.
function(sffd_header_library name)
  cmake_parse_arguments(ARG "" "DIR" "DEPS" ${ARGN})
  add_library(${name} INTERFACE)
  target_include_directories(${name} INTERFACE ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} INTERFACE ${ARG_DEPS})
  target_compile_features(${name} INTERFACE cxx_std_20)
  set_target_properties(${name} PROPERTIES SFFD_HEADER_DIRS "${ARG_DIR}")
  set_property(GLOBAL APPEND PROPERTY SFFD_TARGETS ${name})
endfunction()

# sffd_write_link_graph(file): every project target's sources and link libraries, one line each, for
# tools/check_includes.py (the include-boundary test). Called once, after every target exists.
function(sffd_write_link_graph file)
  get_property(targets GLOBAL PROPERTY SFFD_TARGETS)
  set(text "# name\ttype\tsource_dir\tsources\theader_dirs\tlink_libraries\tinterface_link_libraries\n")
  foreach(t IN LISTS targets)
    get_target_property(type ${t} TYPE)
    get_target_property(dir ${t} SOURCE_DIR)
    file(RELATIVE_PATH dir ${PROJECT_SOURCE_DIR} ${dir})
    get_target_property(sources ${t} SOURCES)
    get_target_property(header_dirs ${t} SFFD_HEADER_DIRS)
    get_target_property(link ${t} LINK_LIBRARIES)
    get_target_property(interface ${t} INTERFACE_LINK_LIBRARIES)
    if(type STREQUAL "INTERFACE_LIBRARY")
      set(link "${interface}")
    endif()
    foreach(v sources header_dirs link interface)
      if(NOT ${v})
        set(${v} "")
      endif()
    endforeach()
    if(dir STREQUAL "")
      set(dir ".")
    endif()
    string(APPEND text "${t}\t${type}\t${dir}\t${sources}\t${header_dirs}\t${link}\t${interface}\n")
  endforeach()
  file(WRITE ${file} "${text}")
endfunction()
