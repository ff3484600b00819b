// ContactSheet.h — a grid of frames across a run in one PNG (`ambience run --contact-sheet`).
//
// The frames are picked evenly over the run (the first and the last among them), each shrunk to
// a cell (OpenImageIO's resize, a filtered downscale) and labelled with its frame index and time
// of day where a font is found; cells fill rows of `columns`.
#pragma once

#include <string>
#include <vector>

namespace amb {

class ContactSheet {
  public:
    // `frames` in the run, `cells` of them on the sheet (at most `frames`), each cell 1/`shrink`
    // of a width x height frame.
    ContactSheet(int frames, int cells, int width, int height, int columns = 4, int shrink = 3);
    // Whether frame `index` (0-based) is one of the sheet's.
    bool wants(int index) const;
    // Adds frame `index` (RGB 8-bit, top row first), labelled.
    void add(int index, const std::vector<unsigned char>& rgb, const std::string& label);
    int cellsAdded() const { return added_; }
    // Writes the sheet (cells not added stay black); throws InputError naming `path`.
    void write(const std::string& path) const;
    int sheetWidth() const { return columns_ * cellW_; }
    int sheetHeight() const { return rows_ * cellH_; }

  private:
    int width_, height_, columns_, rows_, cellW_, cellH_, added_ = 0;
    std::vector<int> picks_;           // frame index per cell
    std::vector<unsigned char> sheet_;  // RGB 8-bit
};

}  // namespace amb
