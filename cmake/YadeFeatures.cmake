# The compile definitions of the installed yade-double, derived from its yade.config.features.
# A plugin must see YADE's headers exactly as Debian's build saw them: one definition missing
# changes the layout of Scene or of a functor, and the plugin then reads garbage without crashing.
# So the definitions are not a hand list: each feature the installed YADE reports is mapped here,
# and a feature this table does not know stops the configuration (a newer YADE needs a look
# before it is trusted). The self-test (engines/yade/selftest.py) then proves the result.
#
# Sets YADE_FEATURES (the installed list) and YADE_DEFINITIONS (for target_compile_definitions).
# YADE_FEATURES_OVERRIDE (a ;-list) replaces the queried list, for the test that builds a plugin
# with one definition wrong.

function(yade_query_features out)
  set(cache "${CMAKE_BINARY_DIR}/yade-features.txt")
  if(EXISTS "${cache}")
    file(READ "${cache}" feats)
  else()
    set(script "${CMAKE_BINARY_DIR}/yade-features.py")
    file(WRITE "${script}" "import sys, yade.config\nprint('FEATURES:' + ';'.join(sorted(set(yade.config.features))))\nsys.stdout.flush()\n")
    execute_process(COMMAND ${YADE_EXECUTABLE} -n -x "${script}"
                    OUTPUT_VARIABLE text ERROR_VARIABLE err RESULT_VARIABLE rc TIMEOUT 300)
    string(REGEX MATCH "FEATURES:[^\n]*" line "${text}")
    if(NOT line)
      message(FATAL_ERROR "could not read yade.config.features from ${YADE_EXECUTABLE} (status ${rc}): ${err}")
    endif()
    string(REPLACE "FEATURES:" "" feats "${line}")
    file(WRITE "${cache}" "${feats}")
  endif()
  string(STRIP "${feats}" feats)
  set(${out} "${feats}" PARENT_SCOPE)
endfunction()

# feature -> definitions it implies in YADE's CMakeLists.txt (2023.02a).
set(_yade_map_LOGGER "YADE_BOOST_LOG;BOOST_LOG_DYN_LINK")
set(_yade_map_COMPLEX_MP "YADE_COMPLEX_MP")
set(_yade_map_OPENMP "YADE_OPENMP")
set(_yade_map_GTS "YADE_GTS")
set(_yade_map_QT5 "YADE_OPENGL;YADE_QT5;QT_NO_KEYWORDS")
set(_yade_map_CGAL "YADE_CGAL;CGAL_DISABLE_ROUNDING_MATH_CHECK")
set(_yade_map_PFVFLOW "FLOW_ENGINE")
set(_yade_map_LINSOLV "LINSOLV")
set(_yade_map_MPI "YADE_MPI")
set(_yade_map_TWOPHASEFLOW "TWOPHASEFLOW")
set(_yade_map_LS_DEM "YADE_LS_DEM")
set(_yade_map_FEMLIKE "YADE_FEM")
set(_yade_map_GL2PS "YADE_GL2PS")
set(_yade_map_LBMFLOW "LBM_ENGINE")
set(_yade_map_THERMAL "THERMAL")
set(_yade_map_PARTIALSAT "PARTIALSAT")
set(_yade_map_POTENTIAL_PARTICLES "YADE_POTENTIAL_PARTICLES")
set(_yade_map_VTK "YADE_VTK")
set(_yade_map_VECTORIZE "")       # its absence adds the EIGEN_DONT_* definitions below
set(_yade_map_USEFUL_ERRORS "")   # warning flags only

if(NOT YADE_EXECUTABLE)
  find_program(YADE_EXECUTABLE yade-double REQUIRED)
endif()
if(DEFINED YADE_FEATURES_OVERRIDE)
  set(YADE_FEATURES "${YADE_FEATURES_OVERRIDE}")
else()
  yade_query_features(YADE_FEATURES)
endif()
list(REMOVE_DUPLICATES YADE_FEATURES)

# Always defined by YADE 2023.02a's build of double precision with Boost >= 1.53.
set(YADE_DEFINITIONS MAX_LOG_LEVEL=5 YADE_REAL_BIT=64 YADE_REAL_DEC=15 YADE_ODEINT)
foreach(f IN LISTS YADE_FEATURES)
  if(NOT DEFINED _yade_map_${f})
    message(FATAL_ERROR "yade-double reports the feature '${f}', which cmake/YadeFeatures.cmake does not know: "
                        "its compile definitions must be added to the table there (read YADE's CMakeLists.txt) "
                        "before a plugin is built against this YADE")
  endif()
  list(APPEND YADE_DEFINITIONS ${_yade_map_${f}})
endforeach()
if(NOT "VECTORIZE" IN_LIST YADE_FEATURES)
  list(APPEND YADE_DEFINITIONS EIGEN_DONT_VECTORIZE EIGEN_DONT_ALIGN EIGEN_DISABLE_UNALIGNED_ARRAY_ASSERT)
endif()
