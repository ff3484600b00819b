// DataPaths.h — where the program finds the data it ships (shaders/, replays/, bench-plots.py),
// relative to its own executable, so that a build tree and an installed copy both work from any
// working directory (README "Install and package"). No GL, no OpenVDB: every layer may ask.
//
// The data folders searched, in order, for an executable in EXE:
//   EXE/<bin to data>   installed: P/bin/ambience -> P/share/ambience (GNUInstallDirs, set by
//                       CMake as AMBIENCE_DATA_FROM_BIN)
//   EXE                 build tree: build/bin holds bench-plots.py
//   EXE/..              build tree: build/ holds the validated shaders/
//   EXE/../..           build tree inside the source tree: the source's replays/
#pragma once

#include <string>
#include <vector>

namespace amb {

// The installed data folder relative to the installed executable's folder ("../share/ambience"
// with CMake's default install folders).
std::string installedDataFromBin();

// The folder of the running executable (/proc/self/exe), or "" when it cannot be read.
std::string executableDirectory();

// The data folders searched for an executable in `exeDirectory`, in order (see above); none
// when `exeDirectory` is empty.
std::vector<std::string> dataFolders(const std::string& exeDirectory);

// The first `<folder>/<relative>` that exists over dataFolders(exeDirectory), normalised
// (no "." or ".." steps); "" when none does. `relative` names a file or a folder
// ("bench-plots.py", "shaders", "replays/highway-drive.json").
std::string findDataFileFrom(const std::string& exeDirectory, const std::string& relative);

// findDataFileFrom(executableDirectory(), relative): what the program itself uses.
std::string findDataFile(const std::string& relative);

}  // namespace amb
