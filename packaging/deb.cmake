# `cpack -G DEB` in the build folder: sim4cv_VERSION_amd64.deb, everything `cmake --install`
# installs, under /usr, with /etc/default/sim4cvd (a conffile). Depends come from
# dpkg-shlibdeps: the runtime libraries the binaries link, nothing from -dev packages.
set(CPACK_PACKAGE_NAME sim4cv)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "simulator daemon for computer vision research, with its clients and tools")
set(CPACK_PACKAGE_DESCRIPTION "sim4cvd renders camera frames with ground truth (depth, masks, boxes, flow) of \
UAV tracking and driving scenes, for clients over TCP, UDP and shared memory; with the C++ client \
library (CMake package and pkg-config), map and run-log tools, shipped maps, models and the studio.")
set(CPACK_PACKAGE_CONTACT "sim4cv developers <noreply@sim4cv.invalid>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # sim4cv_0.1.0_amd64.deb
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA ${CMAKE_CURRENT_SOURCE_DIR}/conffiles)
# The staging install puts etc/ under /usr like every other folder; the package wants /etc.
set(CPACK_PRE_BUILD_SCRIPTS ${CMAKE_CURRENT_SOURCE_DIR}/deb_move_etc.cmake)
set(CPACK_PACKAGE_FILE_NAME sim4cv-${PROJECT_VERSION})  # the staging folder's name
include(CPack)
