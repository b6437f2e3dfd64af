# satmesh_module(NAME SOURCES ... DEPS ...): one static library per core module,
# target satmesh_<NAME>, include root at the repository root ("core/rpc/rpc_model.h").
function(satmesh_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(satmesh_${name} STATIC ${ARG_SOURCES})
  target_include_directories(satmesh_${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(satmesh_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  set_target_properties(satmesh_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
endfunction()

# satmesh_test(NAME SOURCES ... DEPS ...): one GoogleTest executable, discovered by ctest.
function(satmesh_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  # Real data beside the repository (../shared/data); tests GTEST_SKIP when it is absent.
  target_compile_definitions(${name} PRIVATE
    SATMESH_SHARED_DATA_DIR="${PROJECT_SOURCE_DIR}/../shared/data"
    SATMESH_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 600)
endfunction()
