# The board package: `cpack` in a build folder makes epipole_<version>_<arch>.deb with the
# firmware, its systemd unit and udev rules, the board files and the docs (docs/deploy.md).
# Cross builds (aarch64, armhf) make the package for the board; a host build's package adds the
# host tool.
include(GNUInstallDirs)
install(FILES ${PROJECT_SOURCE_DIR}/firmware/service/epipole.service
        DESTINATION lib/systemd/system)
# The flagship board's device rules (its trigger's chip, its cameras' DMA heaps).
install(FILES ${PROJECT_SOURCE_DIR}/board/raspberrypi5-ov9281/udev.rules DESTINATION lib/udev/rules.d
        RENAME 60-epipole.rules)
install(FILES ${PROJECT_SOURCE_DIR}/firmware/service/epipole-modules.conf
        DESTINATION lib/modules-load.d RENAME epipole.conf)
# The virtual board's files are the test command's, not a board's.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/board/ DESTINATION share/epipole/board
        PATTERN vboard EXCLUDE)
# The flagship board's file as the configuration the unit starts (a conffile).
install(FILES ${PROJECT_SOURCE_DIR}/board/raspberrypi5-ov9281/board.yaml DESTINATION /etc/epipole)
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION share/doc/epipole)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION share/doc/epipole/docs)
# Debian's copyright file (the licence, LICENSE at the top of the tree) and changelog, compressed
# as Debian policy wants it.
install(FILES ${PROJECT_SOURCE_DIR}/firmware/service/debian/copyright DESTINATION share/doc/epipole)
set(_changelog_gz ${CMAKE_BINARY_DIR}/changelog.gz)
add_custom_command(OUTPUT ${_changelog_gz}
                   COMMAND gzip -9nc ${PROJECT_SOURCE_DIR}/firmware/service/debian/changelog >
                           ${_changelog_gz}
                   DEPENDS ${PROJECT_SOURCE_DIR}/firmware/service/debian/changelog)
add_custom_target(epipole_changelog ALL DEPENDS ${_changelog_gz})
install(FILES ${_changelog_gz} DESTINATION share/doc/epipole)

# Manual pages made from each program's --help by help2man (Debian's help2man), installed with
# the program. The page is made by running the program: a cross build runs the target's one
# under qemu-user (CMAKE_CROSSCOMPILING_EMULATOR), through a script named as the program, so
# that help2man names the page after it.
find_program(EPIPOLE_HELP2MAN help2man)
function(epipole_man_page target description)
  if(NOT EPIPOLE_HELP2MAN)
    message(WARNING "help2man not found: no manual page for ${target} (scripts/setup.sh installs it)")
    return()
  endif()
  set(folder ${CMAKE_BINARY_DIR}/man)
  list(JOIN CMAKE_CROSSCOMPILING_EMULATOR " " _emulator)
  file(GENERATE OUTPUT ${folder}/bin/${target}
       CONTENT "#!/bin/sh\nexec ${_emulator} \"$<TARGET_FILE:${target}>\" \"$@\"\n"
       FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE
                        WORLD_READ WORLD_EXECUTE)
  set(page ${folder}/${target}.1)
  add_custom_command(
    OUTPUT ${page}.gz
    COMMAND ${EPIPOLE_HELP2MAN} --no-info --no-discard-stderr --section=1
            --version-string=${PROJECT_VERSION} --name=${description} --output=${page}
            ${folder}/bin/${target}
    COMMAND gzip -9nf ${page}
    DEPENDS ${target}
    COMMENT "Manual page of ${target} (help2man)"
    VERBATIM)
  add_custom_target(${target}_man ALL DEPENDS ${page}.gz)
  install(FILES ${page}.gz DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
endfunction()
# Packages come from builds without sanitizers (host, aarch64, armhf).
if(NOT EPIPOLE_SANITIZE)
  epipole_man_page(epipole-fw "Epipole stereo-vision firmware: runs a board's frame loop")
  if(TARGET epipole)
    epipole_man_page(epipole "Epipole's tools at a desk: calibrate, rectify, match, simulate")
  endif()
endif()

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
# The extended description (cpack puts the summary before it).
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION "Epipole runs on the vision board of a robot: two cameras
fired by one trigger, the frame pair rectified, corners, a disparity map and
sparse 3-D points, a Viola-Jones detector with the depth of each detection,
and the results sent to the robot's controller over a serial link (its own
protocol, or MAVLink 2 for PX4 and ArduPilot). It runs as a systemd service
with a watchdog, configured by /etc/epipole/board.yaml.")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_SET_DESTDIR ON)  # /etc/epipole is installed at its absolute path
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE ${_deb_arch})
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
# The dependencies are computed when cpack runs: dpkg-shlibdeps on the binaries the package holds,
# against the libraries of its architecture (scripts/package-depends.sh; for a cross build the
# database of scripts/fetch-target-libs.sh), never typed by hand. The video plugin's libraries
# are recommended: the firmware runs without it. adduser and init-system-helpers
# (deb-systemd-helper) are what the maintainer scripts run.
set(_package_files "\"$<TARGET_FILE:epipole-fw>\"")
if(TARGET epipole)
  string(APPEND _package_files " \"$<TARGET_FILE:epipole>\"")
endif()
if(TARGET epipole_video)
  string(APPEND _package_files " -dRecommends \"$<TARGET_FILE:epipole_video>\"")
endif()
set(_target_libs "")
if(CMAKE_CROSSCOMPILING)
  set(_target_libs "--target-libs \"${EPIPOLE_TARGET_LIBS}\"")
endif()
file(GENERATE OUTPUT ${CMAKE_BINARY_DIR}/EpipoleCPackDepends.cmake CONTENT "\
# Generated by cmake/EpipolePackaging.cmake; read by cpack before it builds the package.
execute_process(
  COMMAND \"${PROJECT_SOURCE_DIR}/scripts/package-depends.sh\" ${_deb_arch} ${_target_libs}
          ${_package_files}
  OUTPUT_VARIABLE _variables RESULT_VARIABLE _status)
if(NOT _status EQUAL 0)
  message(FATAL_ERROR \"scripts/package-depends.sh could not compute the dependencies\")
endif()
string(REGEX MATCH \"shlibs:Depends=([^\\n]*)\" _ \"\${_variables}\")
if(NOT CMAKE_MATCH_1)
  message(FATAL_ERROR \"scripts/package-depends.sh found no dependencies: \${_variables}\")
endif()
set(CPACK_DEBIAN_PACKAGE_DEPENDS \"\${CMAKE_MATCH_1}, adduser, init-system-helpers (>= 1.54~)\")
string(REGEX MATCH \"shlibs:Recommends=([^\\n]*)\" _ \"\${_variables}\")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS \"\${CMAKE_MATCH_1}\")
")
set(CPACK_PROJECT_CONFIG_FILE ${CMAKE_BINARY_DIR}/EpipoleCPackDepends.cmake)
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${PROJECT_SOURCE_DIR}/firmware/service/debian/postinst
    ${PROJECT_SOURCE_DIR}/firmware/service/debian/prerm
    ${PROJECT_SOURCE_DIR}/firmware/service/debian/postrm
    ${PROJECT_SOURCE_DIR}/firmware/service/debian/conffiles)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
