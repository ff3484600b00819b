#!/usr/bin/env bash
# deb-test.sh — the Debian package CPack builds (README "Install and package").
#
#   deb-test.sh CPACK BUILD_DIR VERSION
#
# Runs `cpack -G DEB` on BUILD_DIR's CPackConfig.cmake into a scratch folder and checks the
# package with dpkg-deb: its name and VERSION, the program, shaders, replays, plot script and
# tune's study script under /usr, nothing of the build tree, and the dependencies (the run-time
# programs and data always, the Python modules recommended; the libraries when dpkg-shlibdeps
# was there to find them).
# Exit 0: passed; 1: failed; 77: no dpkg-deb (ctest counts it as skipped).
set -euo pipefail

cpack="$1" build="$(cd "$2" && pwd)" version="$3"
command -v dpkg-deb >/dev/null || { echo "deb-test: skipped, no dpkg-deb"; exit 77; }
scratch="$(mktemp -d "${TMPDIR:-/tmp}/ambience-deb-test.XXXXXX")"
trap 'rm -rf "$scratch"' EXIT
fail() { echo "deb-test: $*" >&2; exit 1; }

"$cpack" -G DEB --config "$build/CPackConfig.cmake" -B "$scratch" >"$scratch/cpack.log" 2>&1 ||
  fail "cpack failed: $(tail -n 5 "$scratch/cpack.log")"
debs=("$scratch"/*.deb)
((${#debs[@]} == 1)) && [[ -f ${debs[0]} ]] || fail "expected one .deb, found: ${debs[*]}"
deb="${debs[0]}"
[[ $(basename "$deb") == "ambience_${version}_$(dpkg --print-architecture).deb" ]] ||
  fail "unexpected file name $(basename "$deb")"

[[ $(dpkg-deb --field "$deb" Package) == ambience ]] || fail "package name is not ambience"
[[ $(dpkg-deb --field "$deb" Version) == "$version" ]] || fail "version is not $version"
for field in Maintainer Description Section; do
  [[ -n $(dpkg-deb --field "$deb" "$field") ]] || fail "no $field"
done

dpkg-deb --contents "$deb" | awk '{print $NF}' >"$scratch/contents"
for f in ./usr/bin/ambience ./usr/share/ambience/shaders/terrain.frag \
         ./usr/share/ambience/shaders/conventions.glsl ./usr/share/ambience/replays/highway-drive.json \
         ./usr/share/ambience/bench-plots.py ./usr/share/ambience/ambience-tune.py; do
  grep -qxF "$f" "$scratch/contents" || fail "$f is not in the package"
done
if grep -E '\.a$|_test$|\.ok$|/glad/' "$scratch/contents"; then fail "build-tree files packaged"; fi

depends=$(dpkg-deb --field "$deb" Depends)
for p in ffmpeg fonts-dejavu-core libegl-mesa0 libgl1-mesa-dri; do
  grep -qE "(^|, )$p( |,|$)" <<<"$depends" || fail "Depends lacks $p: $depends"
done
recommends=$(dpkg-deb --field "$deb" Recommends)
for p in python3-matplotlib python3-optuna python3-sklearn; do
  grep -qE "(^|, )$p( |,|$)" <<<"$recommends" || fail "Recommends lacks $p: $recommends"
done
if grep -q "CPACK_DEBIAN_PACKAGE_SHLIBDEPS \"ON\"" "$build/CPackConfig.cmake"; then
  for p in libopenvdb libopenimageio libosmesa6 libegl1 libglfw3; do
    grep -q "$p" <<<"$depends" || fail "Depends lacks $p (dpkg-shlibdeps): $depends"
  done
fi
echo "deb-test: passed ($(basename "$deb"), $(wc -l <"$scratch/contents") entries)"
