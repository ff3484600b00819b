// ContactSheet_test.cpp — the run's contact sheet: which frames, where, and what lands there.
#include "app/cli/ContactSheet.h"

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <gtest/gtest.h>

namespace amb {
namespace {

TEST(ContactSheet, PicksFramesEvenlyAndPutsEachInItsCell) {
    // 10 frames, 5 cells in rows of 3: frames 0, 2, 5, 7, 9 (rounded i * 9 / 4); each frame a
    // uniform colour of its own, so each cell's lower half (below the label) is that colour,
    // exactly; the sixth cell stays black. Read back with OpenImageIO.
    const int w = 90, h = 60, frames = 10;
    ContactSheet sheet(frames, 5, w, h, 3, 3);
    std::vector<int> wanted;
    for (int i = 0; i < frames; ++i)
        if (sheet.wants(i)) wanted.push_back(i);
    EXPECT_EQ(wanted, (std::vector<int>{0, 2, 5, 7, 9}));
    const auto colour = [](int i) { return std::array<int, 3>{20 * i + 10, 250 - 20 * i, 7 * i}; };
    for (int i = 0; i < frames; ++i) {
        std::vector<unsigned char> rgb(std::size_t(w) * h * 3);
        for (std::size_t p = 0; p < rgb.size(); ++p) rgb[p] = (unsigned char)colour(i)[p % 3];
        sheet.add(i, rgb, "frame " + std::to_string(i));  // frames not picked are ignored
    }
    EXPECT_EQ(sheet.cellsAdded(), 5);
    ASSERT_EQ(sheet.sheetWidth(), 90);
    ASSERT_EQ(sheet.sheetHeight(), 40);
    const std::string path =
        (std::filesystem::temp_directory_path() / "ambience-contact-sheet-test.png").string();
    sheet.write(path);
    OIIO::ImageBuf read(path);
    ASSERT_TRUE(read.read(0, 0, true, OIIO::TypeDesc::UINT8)) << read.geterror();
    ASSERT_EQ(read.spec().width, 90);
    ASSERT_EQ(read.spec().height, 40);
    for (int cell = 0; cell < 6; ++cell) {
        const int cx = (cell % 3) * 30, cy = (cell / 3) * 20;
        const OIIO::ROI lower(cx, cx + 30, cy + 14, cy + 20, 0, 1, 0, 3);
        const auto stats = OIIO::ImageBufAlgo::computePixelStats(read, lower);
        for (int c = 0; c < 3; ++c) {
            const double want = cell < 5 ? colour(wanted[std::size_t(cell)])[c] / 255.0 : 0.0;
            EXPECT_NEAR(stats.min[std::size_t(c)], want, 1e-6) << "cell " << cell;
            EXPECT_NEAR(stats.max[std::size_t(c)], want, 1e-6) << "cell " << cell;
        }
    }
    std::filesystem::remove(path);
}

TEST(ContactSheet, NoMoreCellsThanFrames) {
    ContactSheet sheet(3, 12, 64, 32);
    int wanted = 0;
    for (int i = 0; i < 3; ++i) wanted += sheet.wants(i);
    EXPECT_EQ(wanted, 3);
    EXPECT_EQ(sheet.sheetWidth(), 3 * (64 / 3));
    EXPECT_EQ(sheet.sheetHeight(), 32 / 3);
}

}  // namespace
}  // namespace amb
