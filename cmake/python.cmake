# The Python module `polrig` (docs/python.md): a pybind11 layer (src/python/) over polrig_lib,
# laid out in the build tree as a package, build/python/polrig/, so that
#   PYTHONPATH=build/python python3 -c "import polrig"
# works without installing; `cmake --install` puts the package where the interpreter finds it.
#
# The interpreter is Debian's /usr/bin/python3 when there is one (python3-numpy and python3-pytest
# are installed for it); -DPython3_EXECUTABLE=… chooses another.

if(POLRIG_PYTHON STREQUAL "AUTO")
  if(NOT POLRIG_SANITIZERS STREQUAL "" OR POLRIG_FUZZ)
    set(_want OFF)
    set(_why "sanitizers are on")
  else()
    set(_want AUTO)
  endif()
else()
  set(_want ${POLRIG_PYTHON})
  set(_why "POLRIG_PYTHON=${POLRIG_PYTHON}")
endif()

if(_want)
  if(NOT DEFINED Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
    set(Python3_EXECUTABLE /usr/bin/python3)
  endif()
  if(_want STREQUAL "AUTO")
    find_package(Python3 3.9 COMPONENTS Interpreter Development.Module)
    if(Python3_FOUND)
      find_package(pybind11 2.10 CONFIG)
    endif()
    if(NOT Python3_FOUND OR NOT pybind11_FOUND)
      set(_want OFF)
      set(_why "Python 3 development files or pybind11 not found (Debian: python3-dev pybind11-dev)")
    endif()
  else()
    find_package(Python3 3.9 REQUIRED COMPONENTS Interpreter Development.Module)
    find_package(pybind11 2.10 REQUIRED CONFIG)
  endif()
endif()

if(NOT _want)
  message(STATUS "polrig: Python module off (${_why})")
  return()
endif()
message(STATUS "polrig: Python module for ${Python3_EXECUTABLE} (${Python3_VERSION})")

set(POLRIG_PYTHON_PACKAGE_DIR ${CMAKE_BINARY_DIR}/python/polrig)

pybind11_add_module(polrig_python MODULE NO_EXTRAS
  src/python/module.cpp
  src/python/convert.cpp
  src/python/rig_bindings.cpp
  src/python/study_bindings.cpp
  src/python/dofp_bindings.cpp
  src/python/four_camera_bindings.cpp
  src/python/four_camera_geometry_bindings.cpp
  src/python/calibration_bindings.cpp
  src/python/sky_bindings.cpp
  src/python/compass_bindings.cpp src/python/dofp_calibration_bindings.cpp
  src/python/orientation_bindings.cpp
  src/python/position_bindings.cpp
  src/python/four_camera_calibration_bindings.cpp
  src/python/navigation_bindings.cpp
  src/python/sky_study_bindings.cpp)
target_link_libraries(polrig_python PRIVATE polrig_lib polrig_options TBB::tbb fmt::fmt)
set_target_properties(polrig_python PROPERTIES
  OUTPUT_NAME _polrig
  LIBRARY_OUTPUT_DIRECTORY ${POLRIG_PYTHON_PACKAGE_DIR})

# The package's pure-Python files, copied next to the module at build time.
set(_package_files __init__.py _polrig.pyi py.typed)
set(_copied)
foreach(f IN LISTS _package_files)
  add_custom_command(OUTPUT ${POLRIG_PYTHON_PACKAGE_DIR}/${f}
    COMMAND ${CMAKE_COMMAND} -E copy ${CMAKE_SOURCE_DIR}/python/polrig/${f}
            ${POLRIG_PYTHON_PACKAGE_DIR}/${f}
    DEPENDS ${CMAKE_SOURCE_DIR}/python/polrig/${f})
  list(APPEND _copied ${POLRIG_PYTHON_PACKAGE_DIR}/${f})
endforeach()
add_custom_target(polrig_python_package ALL DEPENDS ${_copied})
add_dependencies(polrig_python polrig_python_package)

# Install where this interpreter looks: the first entry of its sys.path under the install prefix
# (Debian's python3: lib/python3.X/dist-packages under /usr/local).
if(NOT POLRIG_PYTHON_INSTALL_DIR)
  execute_process(
    COMMAND ${Python3_EXECUTABLE} -c
      "import sys; p='${CMAKE_INSTALL_PREFIX}'.rstrip('/') + '/'; d=[s[len(p):] for s in sys.path if s.startswith(p + 'lib/') and s.endswith(('dist-packages', 'site-packages'))]; print(d[0] if d else 'lib/python%d.%d/site-packages' % sys.version_info[:2])"
    OUTPUT_VARIABLE _dir OUTPUT_STRIP_TRAILING_WHITESPACE)
  set(POLRIG_PYTHON_INSTALL_DIR ${_dir} CACHE STRING
      "Where `cmake --install` puts the polrig package, relative to CMAKE_INSTALL_PREFIX")
endif()
install(TARGETS polrig_python LIBRARY DESTINATION ${POLRIG_PYTHON_INSTALL_DIR}/polrig)
foreach(f IN LISTS _package_files)
  install(FILES ${CMAKE_SOURCE_DIR}/python/polrig/${f} DESTINATION ${POLRIG_PYTHON_INSTALL_DIR}/polrig)
endforeach()

# The pytest suite (python/tests), one CTest case per file, labelled "python"; each finds the
# package in the build tree and the polrig executable for the CLI-equality checks.
if(POLRIG_BUILD_TESTS)
  file(GLOB _pytests CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/python/tests/test_*.py)
  foreach(t IN LISTS _pytests)
    get_filename_component(_name ${t} NAME_WE)
    add_test(NAME python.${_name}
      COMMAND ${Python3_EXECUTABLE} -m pytest -q -p no:cacheprovider ${t}
      WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
    set_tests_properties(python.${_name} PROPERTIES LABELS "python"
      ENVIRONMENT "PYTHONPATH=${CMAKE_BINARY_DIR}/python;POLRIG_EXE=$<TARGET_FILE:polrig>;POLRIG_BUILD_DIR=${CMAKE_BINARY_DIR};POLRIG_PYTHON_INSTALL_DIR=${CMAKE_INSTALL_PREFIX}/${POLRIG_PYTHON_INSTALL_DIR};PYTHONDONTWRITEBYTECODE=1;POLRIG_CACHE_DIR=off")
  endforeach()
endif()
