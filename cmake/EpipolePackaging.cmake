# The board package: `cpack` in a build folder makes epipole_<version>_<arch>.deb with the
# firmware, its systemd unit and udev rules, the board files and the docs (docs/deploy.md).
# Cross builds (aarch64, armhf) make the package for the board; a host build's package adds the
# host tool.
include(GNUInstallDirs)
install(FILES ${PROJECT_SOURCE_DIR}/firmware/service/epipole.service
        DESTINATION lib/systemd/system)
install(FILES ${PROJECT_SOURCE_DIR}/firmware/service/60-epipole.rules DESTINATION lib/udev/rules.d)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/board/ DESTINATION share/epipole/board)
# The flagship board's file as the configuration the unit starts (a conffile).
install(FILES ${PROJECT_SOURCE_DIR}/board/raspberrypi5-ov9281/board.yaml DESTINATION /etc/epipole)
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION share/doc/epipole)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION share/doc/epipole/docs)

if(CMAKE_CROSSCOMPILING)
  set(_deb_arch ${EPIPOLE_DEBIAN_ARCH})
else()
  execute_process(COMMAND dpkg --print-architecture OUTPUT_VARIABLE _deb_arch
                  OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
endif()

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME epipole)
set(CPACK_PACKAGE_VENDOR "The Epipole project")
set(CPACK_PACKAGE_CONTACT "Epipole maintainers <maintainers@epipole.invalid>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "Stereo-vision firmware for robot single-board computers")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_SET_DESTDIR ON)  # /etc/epipole is installed at its absolute path
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE ${_deb_arch})
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
# yaml-cpp and libgpiod are linked statically into cross builds; what is left is the C++ runtime.
set(CPACK_DEBIAN_PACKAGE_DEPENDS "libc6 (>= 2.36), libstdc++6 (>= 12), libgcc-s1, adduser")
if(EPIPOLE_HAVE_LIBCAMERA)
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", libcamera0")
endif()
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${PROJECT_SOURCE_DIR}/firmware/service/debian/postinst
    ${PROJECT_SOURCE_DIR}/firmware/service/debian/prerm
    ${PROJECT_SOURCE_DIR}/firmware/service/debian/postrm
    ${PROJECT_SOURCE_DIR}/firmware/service/debian/conffiles)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
