// WorldSettings.h — everything a world is generated from. Same settings, same world, bit for bit.
#pragma once

#include <cstdint>

namespace amb {

struct WorldSettings {
    std::uint64_t seed = 1;          // drives every random choice
    double latitude_deg = 45.0;      // for the sun path
    int dayOfYear = 172;             // 1..365, for the sun's declination (172 = June solstice)
    double waterLevel_m = 0.0;       // height of the sea/lake surface
    double roadRegion_m = 6000.0;    // roads are routed inside [-R, R]^2 around the origin
};

}  // namespace amb
