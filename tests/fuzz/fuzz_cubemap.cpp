// fuzz_cubemap — amb::readCubeMap (lighting/CubeMapFile.h) on arbitrary bytes written to a
// temporary file whose extension (.png, .exr, .hdr) is chosen by the first byte, so one target
// reaches the three decoders OpenImageIO picks by extension. An accepted image has the promised
// shape.
#include "FuzzSupport.h"
#include "lighting/CubeMapFile.h"
#include "world/Error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    static const char* const kExtensions[] = {".png", ".exr", ".hdr"};
    const amb::fuzz::TempInputFile file(data + 1, size - 1, kExtensions[data[0] % 3]);
    amb::CubeMapImage image;
    try {
        image = amb::readCubeMap(file.path());
    } catch (const amb::InputError&) {
        return 0;
    }
    AMB_FUZZ_EXPECT(image.n >= 1);
    AMB_FUZZ_EXPECT(image.rgb.size() == std::size_t(6) * image.n * image.n * 3);
    return 0;
}
