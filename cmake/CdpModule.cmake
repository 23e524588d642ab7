# One static library per module folder (polygonizer/, io/, baselines/, raytrace/, render/):
# sources are src/**/*.cpp (src/ also holds the module's private headers), public headers are
# include/cdp/<name>/*.h, included as <cdp/<name>/...>. The target is cdp_<name>, exported and
# aliased as cdp::<name>. Position-independent always: the Python module (python/) links the
# libraries into a shared object, and the programs and the module must run the same objects
# however the tree was configured (12 polygonize runs of every model and method wrote
# byte-identical meshes with and without it).
function(cdp_add_module name)
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp)
  add_library(cdp_${name} STATIC ${sources})
  add_library(cdp::${name} ALIAS cdp_${name})
  target_include_directories(cdp_${name} PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
                                                $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>
                                         PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src)
  set_target_properties(cdp_${name} PROPERTIES EXPORT_NAME ${name} POSITION_INDEPENDENT_CODE ON)
  # Compiled eight files to a unit: each file instantiated the same Eigen and standard templates
  # again (the precompiled headers save only the parsing), and the libraries were half of make
  # test's build on two cores. So names at file scope, in anonymous namespaces too, are unique
  # within a module (shared helpers go to the module's src/ headers). The meshes are the same bit
  # for bit: no fused multiply-adds (-ffp-contract=off) and no reassociation, whatever is inlined.
  set_target_properties(cdp_${name} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 8)
  # One export set per module, so that find_package(cdp COMPONENTS core) loads cdp::core and
  # looks for Eigen only (cmake/cdpConfig.cmake.in).
  install(TARGETS cdp_${name} EXPORT cdp-${name}-targets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(EXPORT cdp-${name}-targets NAMESPACE cdp:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/cdp)
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()

# The headers most of a module's files include, precompiled once per module by those whose compile
# time is parsing (target_precompile_headers(cdp_<name> PRIVATE ${CDP_COMMON_HEADERS} ...); see
# polygonizer/CMakeLists.txt for which modules and why).
set(CDP_COMMON_HEADERS <algorithm> <cmath> <string> <vector> <Eigen/Dense> <cdp/core/field.h> <cdp/core/mesh.h>)
