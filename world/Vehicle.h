// Vehicle.h — the camera's own car on drives: a coarse body as a plain mesh. Local frame: +Z is
// forward, +Y up, origin on the ground under the driver's eye; the eye sits 1.5 m above it
// (DriveSettings::eyeHeight_m), so the bonnet shows at the bottom of the view.
#pragma once

#include "world/WorldMesh.h"

namespace amb {

WorldMesh makeVehicleMesh();

}  // namespace amb
