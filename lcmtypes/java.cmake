# Java message types for LCM's own inspector, lcm-spy (./rover spy, tools/spy): lcm-gen -j
# output for every lcmtypes/*.lcm, compiled into build/share/java/rover_msgs.jar. Built
# only when a JDK (javac, jar) and LCM's Java library (liblcm-java's lcm.jar) are present;
# the C++ build needs neither.
find_package(Java QUIET COMPONENTS Development)
find_file(LCM_JAR lcm.jar PATHS /usr/share/java /usr/local/share/java NO_DEFAULT_PATH)
if(NOT Java_FOUND OR NOT Java_JAVAC_EXECUTABLE OR NOT Java_JAR_EXECUTABLE OR NOT LCM_JAR)
  message(STATUS "rover_msgs.jar (lcm-spy's message types) skipped: needs a JDK "
                 "(openjdk-17-jdk-headless) and lcm.jar (liblcm-java)")
  return()
endif()

include(UseJava)
set(lcm_java_out ${CMAKE_CURRENT_BINARY_DIR}/java)
set(lcm_java_files)
foreach(f ${lcm_files})
  get_filename_component(n ${f} NAME_WE)
  list(APPEND lcm_java_files ${lcm_java_out}/rover_msgs/${n}.java)
endforeach()
add_custom_command(
  OUTPUT ${lcm_java_files}
  COMMAND ${CMAKE_COMMAND} -E rm -rf ${lcm_java_out}
  COMMAND ${CMAKE_COMMAND} -E make_directory ${lcm_java_out}
  COMMAND ${LCM_GEN} -j --jpath ${lcm_java_out} ${lcm_files}
  DEPENDS ${lcm_files}
  COMMENT "lcm-gen: Java message types")
add_jar(rover_msgs_java
  SOURCES ${lcm_java_files}
  INCLUDE_JARS ${LCM_JAR}
  OUTPUT_NAME rover_msgs
  OUTPUT_DIR ${CMAKE_BINARY_DIR}/share/java)
# For tools/spy (LCM_JAR is a cache variable, seen there too).
set_property(GLOBAL PROPERTY ROVER_MSGS_JAR ${CMAKE_BINARY_DIR}/share/java/rover_msgs.jar)
