# Assembles the Octave package sim4cv-VERSION.tar.gz (`pkg install` it, then `pkg load sim4cv`):
# the .m functions, the examples and the built MEX file in inst/, DESCRIPTION and COPYING.
#   cmake -DSOURCE_DIR=clients/matlab -DMEX=.../sim4cv_mex.mex -DVERSION=0.1.0 -DWORK_DIR=... -DOUTPUT=...tar.gz -P octave_package.cmake
foreach(required SOURCE_DIR MEX VERSION WORK_DIR OUTPUT)
  if(NOT DEFINED ${required})
    message(FATAL_ERROR "octave_package.cmake needs -D${required}=...")
  endif()
endforeach()
set(package_dir ${WORK_DIR}/sim4cv)
file(REMOVE_RECURSE ${WORK_DIR})
file(GLOB functions ${SOURCE_DIR}/*.m ${SOURCE_DIR}/examples/*.m)
file(COPY ${functions} ${MEX} DESTINATION ${package_dir}/inst)
string(TIMESTAMP DATE "%Y-%m-%d" UTC)
configure_file(${SOURCE_DIR}/DESCRIPTION.in ${package_dir}/DESCRIPTION @ONLY)
file(COPY ${SOURCE_DIR}/COPYING DESTINATION ${package_dir})
get_filename_component(output ${OUTPUT} ABSOLUTE)
execute_process(COMMAND ${CMAKE_COMMAND} -E tar czf ${output} sim4cv WORKING_DIRECTORY ${WORK_DIR}
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "octave_package.cmake: tar failed for ${output}")
endif()
