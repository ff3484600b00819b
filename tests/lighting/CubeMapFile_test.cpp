// CubeMapFile_test.cpp — vertical-strip cube-map files: round trip, layout on disk (checked with
// OpenImageIO directly), 8-bit and grey input, bad files named in the error, and tiny files whose
// headers declare huge images refused before anything is allocated.
#include "lighting/CubeMapFile.h"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <boost/crc.hpp>

#include "world/Error.h"

namespace amb {
namespace {

std::string tempPath(const std::string& name) {
    return (std::filesystem::temp_directory_path() /
            ("ambience_cubemapfile_" + std::to_string(::getpid()) + "_" + name))
        .string();
}

// A distinct value per (face, row, column, channel).
float texelValue(int face, int j, int i, int c) {
    return 1000.0f * face + 100.0f * j + 10.0f * i + c + 0.125f;
}

std::vector<float> distinctMap(int n) {
    std::vector<float> rgb(std::size_t(6) * n * n * 3);
    for (int f = 0; f < 6; ++f)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                for (int c = 0; c < 3; ++c)
                    rgb[3 * ((std::size_t(f) * n + j) * n + i) + c] = texelValue(f, j, i, c);
    return rgb;
}

void writeImage(const std::string& path, int w, int h, int channels, OIIO::TypeDesc type,
                const std::vector<float>& data) {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(w, h, channels, type);
    spec.attribute("oiio:UnassociatedAlpha", 1);  // store colour as given, not divided by alpha
    ASSERT_TRUE(out->open(path, spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, data.data()));
    ASSERT_TRUE(out->close());
}

// EXR stores 32-bit float: the round trip is exact, and HDR values (1e5) survive.
TEST(CubeMapFile, ExrRoundTripIsExact) {
    const int n = 5;
    auto rgb = distinctMap(n);
    rgb[7] = 1e5f;
    rgb[8] = 3.5e-7f;
    const std::string path = tempPath("roundtrip.exr");
    writeCubeMap(path, n, rgb);
    const CubeMapImage image = readCubeMap(path);
    EXPECT_EQ(image.n, n);
    EXPECT_EQ(image.rgb, rgb);
    std::filesystem::remove(path);
}

// On disk: width N, height 6N, float, texel (face f, row j, column i) at pixel (i, f N + j).
TEST(CubeMapFile, VerticalStripLayout) {
    const int n = 4;
    const std::string path = tempPath("layout.exr");
    writeCubeMap(path, n, distinctMap(n));
    auto in = OIIO::ImageInput::open(path);
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().width, n);
    EXPECT_EQ(in->spec().height, 6 * n);
    EXPECT_EQ(in->spec().format, OIIO::TypeDesc::FLOAT);
    std::vector<float> pixels(std::size_t(n) * 6 * n * 3);
    ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, pixels.data()));
    for (int f = 0; f < 6; ++f)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                for (int c = 0; c < 3; ++c) {
                    const std::size_t y = std::size_t(f) * n + j;
                    EXPECT_EQ(pixels[3 * (y * n + i) + c], texelValue(f, j, i, c));
                }
    std::filesystem::remove(path);
}

// An 8-bit PNG is read as [0, 1] (within 1/255 quantisation); alpha is ignored (colour is not
// multiplied by it); a grey image fills all three channels.
TEST(CubeMapFile, ReadsEightBitAndGrey) {
    const int n = 2;
    std::vector<float> rgba(std::size_t(n) * 6 * n * 4);
    for (std::size_t t = 0; t < rgba.size() / 4; ++t) {
        rgba[4 * t] = 0.2f;
        rgba[4 * t + 1] = 0.6f;
        rgba[4 * t + 2] = 1.0f;
        rgba[4 * t + 3] = 0.5f;
    }
    const std::string png = tempPath("rgba.png");
    writeImage(png, n, 6 * n, 4, OIIO::TypeDesc::UINT8, rgba);
    const CubeMapImage image = readCubeMap(png);
    ASSERT_EQ(image.rgb.size(), std::size_t(6) * n * n * 3);
    for (std::size_t t = 0; t < image.rgb.size() / 3; ++t) {
        EXPECT_NEAR(image.rgb[3 * t], 0.2f, 0.5f / 255);
        EXPECT_NEAR(image.rgb[3 * t + 1], 0.6f, 0.5f / 255);
        EXPECT_NEAR(image.rgb[3 * t + 2], 1.0f, 0.5f / 255);
    }
    std::filesystem::remove(png);

    const std::string grey = tempPath("grey.exr");
    std::vector<float> g(std::size_t(n) * 6 * n, 0.75f);
    writeImage(grey, n, 6 * n, 1, OIIO::TypeDesc::FLOAT, g);
    const CubeMapImage greyImage = readCubeMap(grey);
    for (float v : greyImage.rgb) EXPECT_EQ(v, 0.75f);
    std::filesystem::remove(grey);
}

// Bad files raise InputError whose message names the file and the problem.
TEST(CubeMapFile, BadFilesNameFileAndProblem) {
    auto expectError = [](const std::string& path, const std::string& problem) {
        try {
            readCubeMap(path);
            ADD_FAILURE() << "no error for " << path;
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(path), std::string::npos) << what;
            EXPECT_NE(what.find(problem), std::string::npos) << what;
        }
    };
    expectError(tempPath("missing.exr"), "cannot read");

    const std::string square = tempPath("square.exr");
    writeImage(square, 4, 4, 3, OIIO::TypeDesc::FLOAT, std::vector<float>(4 * 4 * 3, 1.0f));
    expectError(square, "6N high");
    std::filesystem::remove(square);

    const std::string twoChannels = tempPath("two.exr");
    writeImage(twoChannels, 2, 12, 2, OIIO::TypeDesc::FLOAT, std::vector<float>(2 * 12 * 2, 1.0f));
    expectError(twoChannels, "channels");
    std::filesystem::remove(twoChannels);

    const std::string garbage = tempPath("garbage.exr");
    std::ofstream(garbage) << "this is not an image";
    expectError(garbage, "cannot read");
    std::filesystem::remove(garbage);

    const std::string unwritable = tempPath("no_such_dir") + "/map.exr";
    EXPECT_THROW(writeCubeMap(unwritable, 1, std::vector<float>(18, 1.0f)), InputError);
}

// The output check a command makes before any work: a file no image format writes is refused
// naming the option and the extension; what writeCubeMap can write passes. Nothing is created.
TEST(CubeMapFile, OutputWithoutAWriterIsRefusedBeforeAnyWork) {
    auto expectRefused = [](const std::string& path, const std::string& problem) {
        try {
            checkCubeMapOutput(path, "--out");
            ADD_FAILURE() << "no error for " << path;
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.rfind("--out: ", 0), 0u) << what;
            EXPECT_NE(what.find(path), std::string::npos) << what;
            EXPECT_NE(what.find(problem), std::string::npos) << what;
        }
        EXPECT_FALSE(std::filesystem::exists(path)) << path;
    };
    expectRefused(tempPath("probe.txt"), "'.txt'");
    expectRefused(tempPath("probe.no-such-format"), "'.no-such-format'");
    expectRefused(tempPath("probe"), "no file extension");
    for (const char* name : {"probe.exr", "probe.png", "probe.tif", "probe.hdr"}) {
        const std::string path = tempPath(name);
        EXPECT_NO_THROW(checkCubeMapOutput(path, "--out")) << name;
        EXPECT_FALSE(std::filesystem::exists(path)) << name;
        // What passes the check, writeCubeMap writes.
        writeCubeMap(path, 2, distinctMap(2));
        EXPECT_EQ(readCubeMap(path).n, 2) << name;
        std::filesystem::remove(path);
    }
}

// A PNG of `width` x `height` 8-bit RGB whose only image data is an empty deflate stream: the
// header (IHDR, with its CRC) is valid, the pixels are not there.
std::string pngHeaderOnly(std::uint32_t width, std::uint32_t height) {
    auto be32 = [](std::string& s, std::uint32_t v) {
        for (int shift = 24; shift >= 0; shift -= 8) s.push_back(char((v >> shift) & 0xFF));
    };
    auto chunk = [&](std::string& file, const std::string& type, const std::string& data) {
        be32(file, std::uint32_t(data.size()));
        boost::crc_32_type crc;
        crc.process_bytes(type.data(), type.size());
        crc.process_bytes(data.data(), data.size());
        file += type + data;
        be32(file, crc.checksum());
    };
    std::string ihdr;
    be32(ihdr, width);
    be32(ihdr, height);
    ihdr +=
        std::string("\x08\x02\x00\x00\x00", 5);  // 8 bits, RGB, deflate, no filter, no interlace
    std::string file("\x89PNG\r\n\x1a\n", 8);
    chunk(file, "IHDR", ihdr);
    chunk(file, "IDAT", std::string("\x78\x9c\x03\x00\x00\x00\x00\x01", 8));
    chunk(file, "IEND", "");
    return file;
}

// Found by fuzzing (fuzz_cubemap): a PNG that ends inside a chunk made libpng jump out of
// OpenImageIO's read callback, which leaked the error string (LeakSanitizer). Truncated and
// corrupt chunks are now refused before decoding, naming the chunk; a valid file still reads.
TEST(CubeMapFile, TruncatedOrCorruptPngChunksAreNamed) {
    const std::string png = tempPath("chunks.png");
    writeImage(png, 4, 24, 3, OIIO::TypeDesc::UINT8, std::vector<float>(4 * 24 * 3, 0.5f));
    std::string good;
    {
        std::ifstream in(png, std::ios::binary);
        good.assign(std::istreambuf_iterator<char>(in), {});
    }
    ASSERT_GT(good.size(), 45u);
    // The fuzzer's input: IHDR, then an oFFs chunk of 9 bytes of which 3 are there.
    const std::string truncated = good.substr(0, 33) + std::string("\x00\x00\x00\x09oFFs\x00\x00\x00", 11);
    std::string corrupt = good;
    corrupt[20] ^= 0x01;  // a bit of IHDR's width: its CRC no longer matches
    const struct {
        const std::string* bytes;
        const char* expect;
    } cases[] = {{&truncated, "'oFFs' at byte 33 runs past the end"},
                 {&corrupt, "'IHDR' at byte 8 fails its CRC"},
                 {&good, nullptr}};
    for (const auto& c : cases) {
        std::ofstream(png, std::ios::binary | std::ios::trunc) << *c.bytes;
        try {
            readCubeMap(png);
            EXPECT_EQ(c.expect, nullptr) << "no error";
        } catch (const InputError& e) {
            ASSERT_NE(c.expect, nullptr) << e.what();
            EXPECT_NE(std::string(e.what()).find(c.expect), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(png), std::string::npos) << e.what();
        }
    }
    std::filesystem::remove(png);
}

// A 65-byte PNG declaring 100000 x 600000 pixels (1.4e11 texels) and one declaring 8000 x 48000
// (4.6 GB of floats) are refused from their headers with InputError naming the size, quickly
// and without allocating (before, the first gave bad_alloc and the second allocated 4.6 GB);
// 2049 x 12294, one above the limit, too. The same for a Radiance .hdr header.
TEST(CubeMapFile, HugeDeclaredSizesAreRefusedFromTheHeader) {
    struct Case {
        std::uint32_t w, h;
    };
    for (const Case c : {Case{100000, 600000}, Case{8000, 48000}, Case{2049, 12294}}) {
        const std::string png = tempPath("huge.png");
        const std::string bytes = pngHeaderOnly(c.w, c.h);
        EXPECT_LT(bytes.size(), 100u);
        std::ofstream(png, std::ios::binary) << bytes;
        const auto t0 = std::chrono::steady_clock::now();
        try {
            readCubeMap(png);
            ADD_FAILURE() << "no error for " << c.w << " x " << c.h;
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(std::to_string(c.w) + " x " + std::to_string(c.h)),
                      std::string::npos)
                << what;
            EXPECT_NE(what.find("2048"), std::string::npos) << what;
        }
        EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                  2.0);
        std::filesystem::remove(png);
    }
    const std::string hdr = tempPath("huge.hdr");
    std::ofstream(hdr, std::ios::binary)
        << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 600000 +X 100000\n"
        << std::string(16, '\0');
    EXPECT_THROW(readCubeMap(hdr), InputError);
    std::filesystem::remove(hdr);
}

// The limit is on the face: a 2048-wide strip would be accepted (checked from the header of a
// 2048 x 12288 PNG, which then fails only because its pixels are missing).
TEST(CubeMapFile, LargestFaceIsAcceptedByTheSizeCheck) {
    const std::string png = tempPath("largest.png");
    std::ofstream(png, std::ios::binary) << pngHeaderOnly(2048, 12288);
    try {
        readCubeMap(png);
        ADD_FAILURE() << "a PNG without pixels was read";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.find("6N high"), std::string::npos) << what;
        EXPECT_NE(what.find("cannot decode"), std::string::npos) << what;
    }
    std::filesystem::remove(png);
    int limit_MB = 0;
    ASSERT_TRUE(OIIO::getattribute("limits:imagesize_MB", limit_MB));
    EXPECT_GT(limit_MB, 0);
    EXPECT_LE(limit_MB, 400);  // 6 x 2048^2 x 4 channels x 4 bytes = 384 MB, plus one
}

}  // namespace
}  // namespace amb
