# ros_wheels_fixup.cmake -- work around a packaging defect of the ROS 2 Jazzy PyPI wheels.
#
# Passed ONLY by scripts/bootstrap.sh (and optionally colcon --cmake-args), as
#   cmake -DCMAKE_PROJECT_INCLUDE=<repo>/scripts/cmake/ros_wheels_fixup.cmake ...
# so msg_defs/CMakeLists.txt stays untouched and a real `colcon build` on a ROS Jazzy
# install never sees this file.
#
# Problem: the imported `<pkg>::<pkg>__rosidl_generator_py` targets exported by the wheels
# (std_msgs, geometry_msgs, builtin_interfaces, ...) list the include dirs of the
# manylinux build interpreter, e.g. /opt/python/cp311-cp311/include/python3.11 and
# .../site-packages/numpy/_core/include. Those do not exist here, so CMake's generate step
# fails ("Imported target ... includes non-existent path").
# Fix: at the end of the top-level directory (cmake_language(DEFER), i.e. after
# find_package() created the imported targets, before generation) replace every missing
# include dir of every imported target with ${Python3_INCLUDE_DIRS} and
# ${Python3_NumPy_INCLUDE_DIRS} of the interpreter actually in use.
include_guard(GLOBAL)
if(CMAKE_VERSION VERSION_LESS 3.21)  # IMPORTED_TARGETS dir property, cmake_language(DEFER)
  message(FATAL_ERROR "ros_wheels_fixup.cmake needs CMake >= 3.21 (have ${CMAKE_VERSION})")
endif()

function(_ros_wheels_fixup_include_dirs)
  if(NOT Python3_INCLUDE_DIRS OR NOT Python3_NumPy_INCLUDE_DIRS)
    find_package(Python3 REQUIRED COMPONENTS Interpreter Development.Module NumPy)
  endif()
  get_directory_property(_targets DIRECTORY "${CMAKE_SOURCE_DIR}" IMPORTED_TARGETS)
  set(_fixed 0)
  foreach(_t IN LISTS _targets)
    get_target_property(_dirs ${_t} INTERFACE_INCLUDE_DIRECTORIES)
    if(NOT _dirs)
      continue()
    endif()
    set(_new "")
    set(_changed FALSE)
    foreach(_d IN LISTS _dirs)
      # keep generator expressions and existing paths as they are
      if(_d MATCHES "^\\$<" OR EXISTS "${_d}")
        list(APPEND _new "${_d}")
      elseif(_d MATCHES "numpy")
        list(APPEND _new ${Python3_NumPy_INCLUDE_DIRS})
        set(_changed TRUE)
      else()
        list(APPEND _new ${Python3_INCLUDE_DIRS})
        set(_changed TRUE)
      endif()
    endforeach()
    if(_changed)
      list(REMOVE_DUPLICATES _new)
      set_target_properties(${_t} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_new}")
      math(EXPR _fixed "${_fixed} + 1")
    endif()
  endforeach()
  message(STATUS "ros_wheels_fixup: replaced missing include dirs of ${_fixed} imported target(s) "
                 "with ${Python3_INCLUDE_DIRS};${Python3_NumPy_INCLUDE_DIRS}")
endfunction()

cmake_language(DEFER DIRECTORY "${CMAKE_SOURCE_DIR}" CALL _ros_wheels_fixup_include_dirs)
