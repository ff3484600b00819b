#!/usr/bin/env bash
# layers-check.sh — GL stays in the layers that may hold it (docs/ARCHITECTURE.md "Layers").
#
#   tests/layers-check.sh [ROOT]      (ctest: layers_check; ROOT: the source tree, default ..)
#
# 1. app/cli includes no GL header (glad/, GL/, EGL/, GLFW/), not app/render/Gl.h, and not
#    Dear ImGui's GLFW or OpenGL backends: the window's input comes through app/platform
#    (Platform::keyDown ...), GL work through app/render's functions.
# 2. world/, lighting/ and app/frame/ include no GL header (CMake does not give them glad's
#    folder, but a system GL header would still compile there).
# Before it looks at ROOT, it checks itself on a scratch tree with one such include planted in
# each folder, which it must find. Exit code: 0 the layers hold, 1 they do not (each include on
# stderr as file:line).
set -euo pipefail

root="${1:-$(cd "$(dirname "$0")/.." && pwd)}"
gl='#[[:space:]]*include[[:space:]]*[<"](glad/|GL/|EGL/|GLFW/)'
cli_extra='#[[:space:]]*include[[:space:]]*[<"](app/render/Gl\.h|imgui_impl_glfw\.h|imgui_impl_opengl3\.h)'

# Prints each offending include under TREE as file:line: text; exit status 0 when there is none.
scan() {
    local tree="$1" found=0 hits
    for dir in world lighting app/frame app/cli; do
        [[ -d "$tree/$dir" ]] || continue
        hits="$(grep -rnE --include='*.h' --include='*.cpp' "$gl" "$tree/$dir" || true)"
        if [[ "$dir" == app/cli ]]; then
            hits="$(printf '%s\n%s' "$hits" \
                "$(grep -rnE --include='*.h' --include='*.cpp' "$cli_extra" "$tree/$dir" || true)" |
                sed '/^$/d')"
        fi
        if [[ -n "$hits" ]]; then
            echo "$hits" | sed "s|^$tree/||" >&2
            found=1
        fi
    done
    return "$found"
}

# The check itself: a clean tree passes, and each planted include, alone in it, is found.
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
for planted in "world/A.cpp:#include <GL/gl.h>" "lighting/B.h:#include \"glad/gl.h\"" \
               "app/frame/C.cpp:#  include <EGL/egl.h>" "app/cli/D.cpp:#include <GLFW/glfw3.h>" \
               "app/cli/E.cpp:#include \"app/render/Gl.h\"" "app/cli/F.cpp:#include <imgui_impl_glfw.h>"; do
    file="${planted%%:*}"
    rm -rf "${scratch:?}"/*
    mkdir -p "$scratch/$(dirname "$file")"
    echo '#include "world/World.h"' > "$scratch/$(dirname "$file")/Clean.cpp"
    if ! scan "$scratch" 2>/dev/null; then
        echo "layers-check: the check itself fails a clean tree" >&2
        exit 1
    fi
    echo "${planted#*:}" > "$scratch/$file"
    if scan "$scratch" 2>/dev/null; then
        echo "layers-check: the check itself missed '${planted#*:}' in $file" >&2
        exit 1
    fi
done

if ! scan "$root"; then
    echo "layers-check: GL included outside app/render and app/platform (above; docs/ARCHITECTURE.md \"Layers\")" >&2
    exit 1
fi
echo "layers-check: app/cli, app/frame, lighting and world include no GL"
