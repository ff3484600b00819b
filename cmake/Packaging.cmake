# Packaging.cmake — CPack: a Debian package of what `cmake --install` installs (README "Install
# and package"). `cpack -G DEB` in the build folder (or the `package` target) writes
# ambience_<version>_<arch>.deb; files go under /usr (bin/ambience, share/ambience, share/doc).
#
# Library dependencies come from dpkg-shlibdeps (package dpkg-dev) reading the executable;
# the rest are what the program starts or opens at run time:
#   ffmpeg              the run's video (started as a program)
#   fonts-dejavu-core   the contact sheet's labels
#   libegl-mesa0        Mesa's EGL driver (libEGL only dispatches to it)
#   libgl1-mesa-dri     Mesa's software rasteriser (llvmpipe) behind EGL surfaceless
#   python3             bench's plot script and tune's study; python3-matplotlib is
#                       recommended (without it bench writes its tables and skips the plots),
#                       python3-optuna and python3-sklearn too (`ambience tune` and its
#                       parameter importances)

set(CPACK_PACKAGE_NAME ambience)
set(CPACK_PACKAGE_VENDOR "Ambience")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "procedural terrain sandbox with a dynamic ambience volume")
set(CPACK_PACKAGE_DESCRIPTION
    "Ambience renders a procedural open world headless (EGL or OSMesa) or in a window, lit by\n\
ambient light sampled at run time around a moving camera: order-2 spherical harmonics\n\
from small cube maps of the coarse scene, stored sparsely, blended over time and\n\
interpolated continuously. It ships replays (camera paths), measures speed against\n\
error (ambience bench) and writes its anchor store as an OpenVDB file.")
set(AMBIENCE_PACKAGE_MAINTAINER "Ambience maintainers <maintainers@ambience.invalid>"
    CACHE STRING "Maintainer field of the Debian package")
set(CPACK_PACKAGE_CONTACT ${AMBIENCE_PACKAGE_MAINTAINER})
set(CPACK_PACKAGE_INSTALL_DIRECTORY ambience)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_GENERATOR DEB)

set(CPACK_DEBIAN_PACKAGE_NAME ambience)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_MAINTAINER ${AMBIENCE_PACKAGE_MAINTAINER})
set(CPACK_DEBIAN_PACKAGE_SECTION graphics)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_DEPENDS
    "ffmpeg, fonts-dejavu-core, libegl-mesa0, libgl1-mesa-dri, python3")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3-matplotlib, python3-optuna, python3-sklearn")
find_program(AMBIENCE_DPKG_SHLIBDEPS dpkg-shlibdeps)
if(AMBIENCE_DPKG_SHLIBDEPS)
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
else()
  message(STATUS "dpkg-shlibdeps not found (package dpkg-dev): the .deb will list only the "
                 "non-library dependencies")
endif()

include(CPack)
