#!/usr/bin/env python3
"""List a saved anchor store (`ambience run --save-anchors F.vdb`) with OpenVDB's own Python
module, and optionally check it (docs/ARCHITECTURE.md "Anchor store", README "Anchor files").

Usage:
  anchor-store-info.py F.vdb                     file metadata, then each grid: type, voxel
                                                 size, active voxels
  anchor-store-info.py F.vdb --expect-anchors N  the same, then checks: the format, N anchors
                                                 in the metadata, every grid of the format
                                                 present with its type, every payload grid
                                                 readable here holding one voxel per anchor at
                                                 the same places, values in range

Needs pyopenvdb (Debian: python3-openvdb, for Debian's python3). Debian's pyopenvdb reads
bool, float and vec3s grids only; the int32 grids (anchor_index_L*, flags) and the vec3d grid
(captured_position) are named with their type but not read. Exit codes: 0 listed (and checks
passed), 1 a check failed, 2 bad arguments or unreadable file, 77 no pyopenvdb.
"""
import argparse
import math
import re
import sys

FORMAT = "ambience-anchor-store-v2"
SH_COEFFICIENTS = 9


def expected_grids(levels):
    """The grids of the format and their OpenVDB tree types (lighting/AnchorStore.cpp save)."""
    grids = [(f"anchor_index_L{level}", "Tree_int32_5_4_3") for level in range(levels)]
    for k in range(SH_COEFFICIENTS):
        for what in ("sh_current", "sh_target", "sh_blend_from"):
            grids.append((f"{what}_{k}", "Tree_vec3s_5_4_3"))
    grids.append(("captured_position", "Tree_vec3d_5_4_3"))
    for name in ("age_s", "lifetime_s", "blend_elapsed_s", "presence", "since_birth_s",
                 "capture_time_of_day_h"):
        grids.append((name, "Tree_float_5_4_3"))
    grids.append(("flags", "Tree_int32_5_4_3"))
    return grids


def read_grid(vdb, path, name):
    """(grid, None) when pyopenvdb reads it; (None, tree type) when it names a type it cannot
    read; (None, None) when the file has no such grid."""
    try:
        return vdb.read(path, name), None
    except TypeError as error:  # "Tree_int32_5_4_3 is not a supported OpenVDB grid type"
        found = re.search(r"(Tree_\w+)", str(error))
        return None, found.group(1) if found else "unsupported"
    except KeyError:
        return None, None


def active_coords(grid):
    """The index coordinates of the grid's active voxels (each anchor is one voxel)."""
    coords = set()
    for item in grid.citerOnValues():
        lo, hi = item["min"], item["max"]
        if lo != hi:  # an active tile, not a voxel: the format has none
            raise ValueError(f"{grid.name}: active tile {lo}..{hi}")
        coords.add(tuple(lo))
    return coords


def values(grid):
    return [item["value"] for item in grid.citerOnValues()]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("file")
    parser.add_argument("--expect-anchors", type=int, default=None)
    args = parser.parse_args()
    try:
        import pyopenvdb as vdb
    except ImportError as error:
        sys.stderr.write(f"anchor-store-info: cannot import pyopenvdb ({error}); install "
                         "python3-openvdb and run with Debian's python3\n")
        return 77

    try:
        meta = vdb.readMetadata(args.file)
    except (OSError, RuntimeError, ValueError) as error:
        sys.stderr.write(f"anchor-store-info: {args.file}: {error}\n")
        return 2
    print(f"{args.file}: file metadata")
    for key in sorted(meta):
        print(f"  {key} = {meta[key]}")

    problems = []
    levels = meta.get("levels")
    if not isinstance(levels, int) or not 1 <= levels <= 16:
        problems.append(f"metadata 'levels' is {levels!r}, expected 1 to 16")
        levels = 0
    anchors = args.expect_anchors
    coords_seen = None
    print("grids:")
    for name, tree_type in expected_grids(levels):
        grid, other = read_grid(vdb, args.file, name)
        if grid is None and other is None:
            print(f"  {name:24s} missing")
            problems.append(f"grid '{name}' is missing")
            continue
        if grid is None:
            print(f"  {name:24s} {other:18s} (not readable by pyopenvdb)")
            if other != tree_type:
                problems.append(f"grid '{name}' has type {other}, expected {tree_type}")
            continue
        count = grid.activeVoxelCount()
        voxel = grid.transform.voxelSize()
        print(f"  {name:24s} {grid.valueTypeName:18s} voxel {voxel[0]:g} m, "
              f"{count} active voxels, file_voxel_count {grid.metadata.get('file_voxel_count')}")
        if anchors is None:
            continue
        # Every payload grid holds one voxel per anchor, all at the anchors' fine positions.
        if count != anchors:
            problems.append(f"grid '{name}': {count} active voxels, expected {anchors}")
        coords = active_coords(grid)
        if any(c[1] != 0 for c in coords):
            problems.append(f"grid '{name}': a voxel off the ground plane (y != 0)")
        if coords_seen is None:
            coords_seen = coords
        elif coords != coords_seen:
            problems.append(f"grid '{name}': active voxels at other places than the first grid's")
        flat = [x for v in values(grid) for x in (v if isinstance(v, tuple) else (v,))]
        if not all(math.isfinite(x) for x in flat):
            problems.append(f"grid '{name}': a value is not finite")
        if name == "presence" and not all(0.0 <= x <= 1.0 for x in flat):
            problems.append("grid 'presence': a value outside [0, 1]")
        if name == "lifetime_s" and not all(x > 0.0 for x in flat):
            problems.append("grid 'lifetime_s': a lifetime that is not positive")

    if anchors is not None:
        if meta.get("format") != FORMAT:
            problems.append(f"metadata 'format' is {meta.get('format')!r}, expected {FORMAT!r}")
        if meta.get("anchors") != anchors:
            problems.append(f"metadata 'anchors' is {meta.get('anchors')!r}, expected {anchors}")
        if not re.fullmatch(r"[0-9a-f]{8}", str(meta.get("checksum_crc32", ""))):
            problems.append("metadata 'checksum_crc32' is not 8 hex digits")
    for p in problems:
        sys.stderr.write(f"anchor-store-info: {args.file}: {p}\n")
    if anchors is not None:
        print("checks: " + ("passed" if not problems else f"{len(problems)} failed"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
