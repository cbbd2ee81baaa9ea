# The Debian package, made by CPack from the install rules of the "runtime" component: the
# program, its run-time data (share/liveprobe), the man page and the bash completion, with
# /usr/share/doc/liveprobe/{copyright,changelog.gz} and the manual (README.md, docs/). The libraries, headers and CMake config
# stay out of it (they are for building against liveprobe, from the tree). Run-time dependencies
# are found by dpkg-shlibdeps. scripts/package builds it and checks it with lintian.
set(doc_dir ${CMAKE_BINARY_DIR}/package-doc)
string(TIMESTAMP changelog_date "%a, %d %b %Y %H:%M:%S +0000" UTC)
file(WRITE ${doc_dir}/changelog
  "liveprobe (${PROJECT_VERSION}) unstable; urgency=medium\n\n"
  "  * Built from the liveprobe source with CPack.\n\n"
  " -- liveprobe developers <maintainers@liveprobe.invalid>  ${changelog_date}\n")
add_custom_command(OUTPUT ${doc_dir}/changelog.gz
  COMMAND gzip -9n -c ${doc_dir}/changelog > ${doc_dir}/changelog.gz
  DEPENDS ${doc_dir}/changelog)
add_custom_target(liveprobe_package_doc ALL DEPENDS ${doc_dir}/changelog.gz)
add_dependencies(liveprobe liveprobe_package_doc)
install(FILES ${CMAKE_SOURCE_DIR}/cmake/package/copyright ${doc_dir}/changelog.gz
        DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT runtime)
# The manual as the source has it: README.md, and docs/ (its pages and their pictures) beside it,
# so the README's links and the pages' own resolve in /usr/share/doc/liveprobe as in the tree.
install(FILES ${CMAKE_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT runtime)
install(DIRECTORY ${CMAKE_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/docs
        COMPONENT runtime FILES_MATCHING PATTERN "*.md" PATTERN "*.png" PATTERN "measurements" EXCLUDE)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME liveprobe)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_PACKAGE_CONTACT "liveprobe developers <maintainers@liveprobe.invalid>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "real-time diffuse lighting from panoramas with nine SH coefficients")
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION
    "liveprobe computes the nine spherical-harmonic coefficients of the diffuse\n\
light an environment casts (Ramamoorthi and Hanrahan, 2001) from panoramas:\n\
still maps, recordings, image sequences and V4L2 cameras, in equirect,\n\
angular, mirror-ball, dual-fisheye and cube layouts. It re-projects them every\n\
frame, lights a model with them in a window or headless, and exports them to\n\
engines (three.js, Babylon.js, Filament, Unity, glTF, WebXR), a WebSocket\n\
stream and MQTT.")
set(CPACK_DEBIAN_PACKAGE_SECTION graphics)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_HOMEPAGE https://github.com/liveprobe/liveprobe)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME liveprobe)
set(CPACK_DEBIAN_RUNTIME_FILE_NAME DEB-DEFAULT)
# Directories the package owns are 0755, files 0644 (lintian's expectations).
set(CPACK_INSTALL_DEFAULT_DIRECTORY_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ
    GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
include(CPack)
