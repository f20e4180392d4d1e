#pragma once
// Angles: one pi, one conversion each way.
namespace pbnbv {

inline constexpr double kPi = 3.14159265358979323846;

constexpr double deg_to_rad(double deg) { return deg * (kPi / 180.0); }
constexpr double rad_to_deg(double rad) { return rad * (180.0 / kPi); }

}  // namespace pbnbv
