// ContactSheet.cpp — see ContactSheet.h.
#include "app/cli/ContactSheet.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include "app/cli/RunReport.h"
#include "world/Error.h"

namespace amb {

ContactSheet::ContactSheet(int frames, int cells, int width, int height, int columns, int shrink)
    : width_(width), height_(height) {
    cells = std::max(0, std::min(cells, frames));
    columns_ = std::max(1, std::min(columns, std::max(cells, 1)));
    rows_ = std::max(1, (cells + columns_ - 1) / columns_);
    cellW_ = std::max(1, width / std::max(shrink, 1));
    cellH_ = std::max(1, height / std::max(shrink, 1));
    for (int k = 0; k < cells; ++k)
        picks_.push_back(cells == 1 ? 0
                                    : int(std::lround(double(k) * (frames - 1) / (cells - 1))));
    sheet_.assign(std::size_t(sheetWidth()) * sheetHeight() * 3, 0);
}

bool ContactSheet::wants(int index) const {
    return std::binary_search(picks_.begin(), picks_.end(), index);
}

void ContactSheet::add(int index, const std::vector<unsigned char>& rgb, const std::string& label) {
    const auto at = std::lower_bound(picks_.begin(), picks_.end(), index);
    if (at == picks_.end() || *at != index) return;
    if (rgb.size() != std::size_t(width_) * height_ * 3) return;
    const int cell = int(at - picks_.begin());
    const OIIO::ImageBuf frame(OIIO::ImageSpec(width_, height_, 3, OIIO::TypeDesc::UINT8),
                               const_cast<unsigned char*>(rgb.data()));
    OIIO::ImageBuf small = OIIO::ImageBufAlgo::resize(frame, "", 0.0f,
                                                      OIIO::ROI(0, cellW_, 0, cellH_, 0, 1, 0, 3));
    // The label in the cell's corner; without a font the cell stays unlabelled.
    const float white[3] = {1.0f, 1.0f, 1.0f};
    OIIO::ImageBufAlgo::render_text(small, 4, 4 + std::max(10, cellH_ / 12), label,
                                    std::max(10, cellH_ / 12), "DejaVuSans", white);
    (void)small.geterror();  // no font: no label
    const int cx = (cell % columns_) * cellW_, cy = (cell / columns_) * cellH_;
    std::vector<unsigned char> pixels(std::size_t(cellW_) * cellH_ * 3);
    small.get_pixels(OIIO::ROI(0, cellW_, 0, cellH_, 0, 1, 0, 3), OIIO::TypeDesc::UINT8,
                     pixels.data());
    for (int y = 0; y < cellH_; ++y)
        std::copy_n(&pixels[std::size_t(y) * cellW_ * 3], std::size_t(cellW_) * 3,
                    &sheet_[(std::size_t(cy + y) * sheetWidth() + cx) * 3]);
    ++added_;
}

void ContactSheet::write(const std::string& path) const {
    writeImageRgb8(path, sheetWidth(), sheetHeight(), sheet_);
}

}  // namespace amb
