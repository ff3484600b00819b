// Vehicle.cpp — the car: a body lofted through eight cross-sections (hexagons: sill, belt line,
// roof edge on each side), its upper bands glass around the cabin; four wheels (12-sided
// cylinders standing on y = 0); head and tail lights as small boxes. Every part is a closed
// surface, flat shaded (each triangle its own vertices, normal and albedo).
#include "world/Vehicle.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <glm/geometric.hpp>

#include "world/Conventions.h"

namespace amb {

namespace {

using Vec3 = glm::dvec3;

const glm::vec3 kPaint(0.05f, 0.14f, 0.45f);
const glm::vec3 kGlass(0.02f, 0.025f, 0.03f);
const glm::vec3 kUnderside(0.04f, 0.04f, 0.04f);
const glm::vec3 kTyre(0.02f, 0.02f, 0.02f);
const glm::vec3 kRim(0.45f, 0.45f, 0.47f);
const glm::vec3 kHeadlight(0.90f, 0.88f, 0.78f);
const glm::vec3 kTaillight(0.80f, 0.04f, 0.03f);

// Appends one triangle with its own flat normal. If `inside` is given and the winding would make
// the normal face it, the winding is turned round (so every part's normals face outward).
void addTriangle(WorldMesh& m, Vec3 a, Vec3 b, Vec3 c, const glm::vec3& albedo,
                 const Vec3* inside = nullptr) {
    Vec3 n = glm::cross(b - a, c - a);
    if (inside && glm::dot(n, (a + b + c) / 3.0 - *inside) < 0.0) {
        std::swap(b, c);
        n = -n;
    }
    n = glm::normalize(n);
    const auto base = std::uint32_t(m.vertexCount());
    for (const Vec3& p : {a, b, c}) {
        m.positions.insert(m.positions.end(), {float(p.x), float(p.y), float(p.z)});
        m.normals.insert(m.normals.end(), {float(n.x), float(n.y), float(n.z)});
        m.albedo.insert(m.albedo.end(), {albedo.r, albedo.g, albedo.b});
    }
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2});
}

void addQuad(WorldMesh& m, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
             const glm::vec3& albedo, const Vec3& inside) {
    addTriangle(m, a, b, c, albedo, &inside);
    addTriangle(m, a, c, d, albedo, &inside);
}

// A cross-section of the body at z: sill (bottom), belt line and roof edge, each at a height and
// a half width. `glassSides` / `glassRoof`: the upper side bands / the top band of the segment
// from this station to the next are glass.
struct Station {
    double z, yBottom, yBelt, yTop, wBottom, wBelt, wTop;
    bool glassSides, glassRoof;
    std::array<Vec3, 6> points() const {
        return {Vec3(wBottom, yBottom, z), Vec3(wBelt, yBelt, z),  Vec3(wTop, yTop, z),
                Vec3(-wTop, yTop, z),      Vec3(-wBelt, yBelt, z), Vec3(-wBottom, yBottom, z)};
    }
};

// Rear to front: boot, rear window, roof, windscreen, bonnet.
constexpr Station kStations[] = {
    {VehicleShape::kRearZ_m, 0.40, 0.80, 0.92, 0.80, 0.84, 0.74, false, false},
    {-2.80, 0.36, 0.88, 1.00, 0.84, 0.88, 0.78, false, false},
    {-2.30, 0.36, 0.93, 1.04, 0.85, 0.88, 0.78, true, true},     // rear window
    {-1.75, 0.36, 0.96, 1.40, 0.85, 0.88, 0.66, true, false},    // side windows, roof
    {-0.40, 0.36, 0.97, VehicleShape::kRoofY_m, 0.85, 0.88, 0.68, true, true},  // windscreen
    {0.40, 0.36, 0.95, 1.00, 0.85, 0.88, 0.80, false, false},
    {1.05, 0.36, 0.86, 0.90, 0.85, 0.87, 0.80, false, false},
    {VehicleShape::kFrontZ_m, 0.40, 0.70, 0.80, 0.80, 0.84, 0.72, false, false},
};

void addBody(WorldMesh& m) {
    constexpr int kCount = int(sizeof(kStations) / sizeof(kStations[0]));
    for (int s = 0; s + 1 < kCount; ++s) {
        const Station& a = kStations[s];
        const Station& b = kStations[s + 1];
        const auto pa = a.points(), pb = b.points();
        const Vec3 axis(0.0, 0.5 * (a.yBottom + a.yTop), 0.5 * (a.z + b.z));
        for (int j = 0; j < 6; ++j) {
            const int k = (j + 1) % 6;
            glm::vec3 albedo = kPaint;
            if (j == 5) albedo = kUnderside;                      // sill to sill
            if ((j == 1 || j == 3) && a.glassSides) albedo = kGlass;  // side windows
            if (j == 2 && a.glassRoof) albedo = kGlass;           // windscreen, rear window
            addQuad(m, pa[j], pa[k], pb[k], pb[j], albedo, axis);
        }
    }
    // End caps: convex hexagons, fanned.
    for (const Station* st : {&kStations[0], &kStations[kCount - 1]}) {
        const auto p = st->points();
        const Vec3 centre(0.0, 0.5 * (st->yBottom + st->yTop), st->z - (st == kStations ? -1 : 1));
        for (int j = 1; j + 1 < 6; ++j) addTriangle(m, p[0], p[j], p[j + 1], kPaint, &centre);
    }
}

// A box [lo, hi] (12 triangles).
void addBox(WorldMesh& m, const Vec3& lo, const Vec3& hi, const glm::vec3& albedo) {
    const Vec3 c = 0.5 * (lo + hi);
    auto corner = [&](int i) {
        return Vec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    };
    static const int faces[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                    {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
    for (const auto& f : faces)
        addQuad(m, corner(f[0]), corner(f[1]), corner(f[2]), corner(f[3]), albedo, c);
}

// A wheel: a 12-sided cylinder about the x axis at (x, r, z), `width_m` wide, one vertex at its
// bottom so that it touches y = 0. The outer face shows the rim.
void addWheel(WorldMesh& m, double x, double z, double radius_m, double width_m) {
    constexpr int kSides = 12;
    const double y = radius_m;
    const double xo = x + (x > 0 ? 0.5 : -0.5) * width_m, xi = x - (x > 0 ? 0.5 : -0.5) * width_m;
    const Vec3 centre(x, y, z);
    auto rimPoint = [&](double px, int i) {
        const double a = 2.0 * kPi * i / kSides;
        return Vec3(px, y - radius_m * std::cos(a), z + radius_m * std::sin(a));
    };
    for (int i = 0; i < kSides; ++i) {
        const Vec3 o0 = rimPoint(xo, i), o1 = rimPoint(xo, i + 1);
        const Vec3 i0 = rimPoint(xi, i), i1 = rimPoint(xi, i + 1);
        addQuad(m, o0, o1, i1, i0, kTyre, centre);
        const Vec3 capO(xo, y, z), capI(xi, y, z);
        addTriangle(m, capO, o0, o1, kRim, &centre);
        addTriangle(m, capI, i0, i1, kTyre, &centre);
    }
}

}  // namespace

WorldMesh makeVehicleMesh() {
    WorldMesh m;
    addBody(m);
    const double r = VehicleShape::kWheelRadius_m, track = 0.80, width = 0.24;
    for (double z : {VehicleShape::kRearAxleZ_m, VehicleShape::kFrontAxleZ_m})
        for (double x : {-track, track}) addWheel(m, x, z, r, width);
    for (double s : {-1.0, 1.0}) {
        const double x0 = s * 0.50, x1 = s * 0.76;
        addBox(m, {std::min(x0, x1), 0.60, VehicleShape::kFrontZ_m - 0.03},
               {std::max(x0, x1), 0.69, VehicleShape::kFrontZ_m + 0.03}, kHeadlight);
        addBox(m, {std::min(x0, x1), 0.72, VehicleShape::kRearZ_m - 0.03},
               {std::max(x0, x1), 0.80, VehicleShape::kRearZ_m + 0.03}, kTaillight);
    }
    return m;
}

glm::dvec3 vehicleForward(const VehiclePose& pose) {
    const double c = std::cos(pose.pitch_rad);
    return {std::sin(pose.heading_rad) * c, std::sin(pose.pitch_rad),
            std::cos(pose.heading_rad) * c};
}

VehiclePose vehiclePoseFromEye(const CameraSample& eye, double eyeHeight_m,
                               const std::function<double(double, double)>& groundHeight) {
    VehiclePose pose;
    pose.position_m = eye.position_m - glm::dvec3(0.0, eyeHeight_m, 0.0);
    const glm::dvec3 f = eye.forward;
    pose.heading_rad = (std::abs(f.x) + std::abs(f.z) > 1e-12) ? std::atan2(f.x, f.z) : 0.0;
    if (groundHeight) {
        // Pitch to the ground under the axles (the wheels' contact points, on the centreline).
        const glm::dvec3 ahead(std::sin(pose.heading_rad), 0.0, std::cos(pose.heading_rad));
        const glm::dvec3 front = pose.position_m + VehicleShape::kFrontAxleZ_m * ahead;
        const glm::dvec3 rear = pose.position_m + VehicleShape::kRearAxleZ_m * ahead;
        const double rise = groundHeight(front.x, front.z) - groundHeight(rear.x, rear.z);
        pose.pitch_rad =
            std::atan2(rise, VehicleShape::kFrontAxleZ_m - VehicleShape::kRearAxleZ_m);
    }
    return pose;
}

WorldMesh pitchedMesh(const WorldMesh& mesh, double pitch_rad) {
    WorldMesh out = mesh;
    const float c = float(std::cos(pitch_rad)), s = float(std::sin(pitch_rad));
    for (auto* v : {&out.positions, &out.normals}) {
        for (std::size_t i = 0; i + 2 < v->size(); i += 3) {
            const float y = (*v)[i + 1], z = (*v)[i + 2];
            (*v)[i + 1] = y * c + z * s;  // nose up: +Z rises
            (*v)[i + 2] = z * c - y * s;
        }
    }
    return out;
}

}  // namespace amb
