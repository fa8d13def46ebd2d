# Unity builds of relief's own targets: each target's .cpp files are compiled
# in batches, one generated file per batch that #includes its sources. On 2
# cores a cold build of the relief program takes about half the time: the
# standard, fmt and JSON headers are parsed once a batch instead of once a
# file, and templates are instantiated and optimised once a batch.
#
# CMake's own UNITY_BUILD includes sources by absolute path, which puts the
# checkout's path into every preprocessed batch, so ccache misses in any
# other clone of the same sources (CI's clean clone). Here the batches
# include their sources by paths relative to the generated file, which are
# the same in every clone whose build directory sits at the same depth in it
# (build/, build-asan/, ...).
#
# A source with properties of its own (compile definitions or options) stays
# out of the batches. Names at namespace scope in anonymous namespaces must be
# distinct within a target (they share a translation unit).

option(RELIEF_UNITY "Compile relief's targets in batches of RELIEF_UNITY_BATCH files" ON)
set(RELIEF_UNITY_BATCH 8 CACHE STRING "Sources per unity batch")

# Remembers a target for relief_unity_apply (relief_warnings calls it).
function(relief_unity_register target)
  set_property(GLOBAL APPEND PROPERTY RELIEF_UNITY_TARGETS ${target})
endfunction()

function(relief_unity_target target)
  get_target_property(source_dir ${target} SOURCE_DIR)
  get_target_property(binary_dir ${target} BINARY_DIR)
  get_target_property(sources ${target} SOURCES)
  set(batchable)
  foreach(source IN LISTS sources)
    if(NOT source MATCHES "\\.cpp$")
      continue()
    endif()
    cmake_path(ABSOLUTE_PATH source BASE_DIRECTORY ${source_dir} NORMALIZE OUTPUT_VARIABLE path)
    get_source_file_property(defs ${path} TARGET_DIRECTORY ${target} COMPILE_DEFINITIONS)
    get_source_file_property(opts ${path} TARGET_DIRECTORY ${target} COMPILE_OPTIONS)
    if(defs OR opts)
      continue()
    endif()
    list(APPEND batchable ${path})
  endforeach()
  list(LENGTH batchable count)
  if(count LESS 2)
    return()
  endif()
  set(out_dir ${binary_dir}/unity)
  set(batch 0)
  set(index 0)
  set(content "")
  set(generated)
  foreach(path IN LISTS batchable)
    file(RELATIVE_PATH relative ${out_dir} ${path})
    string(APPEND content "#include \"${relative}\"\n")
    math(EXPR index "${index} + 1")
    math(EXPR full "${index} % ${RELIEF_UNITY_BATCH}")
    if(full EQUAL 0 OR index EQUAL count)
      set(file ${out_dir}/${target}_${batch}.cpp)
      file(CONFIGURE OUTPUT ${file} CONTENT "// Generated (cmake/relief_unity.cmake)\n${content}")
      list(APPEND generated ${file})
      set(content "")
      math(EXPR batch "${batch} + 1")
    endif()
  endforeach()
  set_source_files_properties(${batchable} TARGET_DIRECTORY ${target}
    PROPERTIES HEADER_FILE_ONLY ON)
  # A quoted #include in a source is looked up beside that source first, so
  # its private headers are found as before.
  target_sources(${target} PRIVATE ${generated})
  # GCC warns of a type from an anonymous namespace used in a type of an
  # included file (no longer "the main file"); within one target it is not a
  # linkage problem.
  target_compile_options(${target} PRIVATE -Wno-subobject-linkage)
endfunction()

# Called once, after every target is defined.
function(relief_unity_apply)
  if(NOT RELIEF_UNITY)
    return()
  endif()
  get_property(targets GLOBAL PROPERTY RELIEF_UNITY_TARGETS)
  foreach(target IN LISTS targets)
    get_target_property(dir ${target} SOURCE_DIR)
    if(dir MATCHES "^${PROJECT_SOURCE_DIR}/(libs|apps)/")
      relief_unity_target(${target})
    endif()
  endforeach()
endfunction()
