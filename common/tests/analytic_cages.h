// Analytic test cages with known enclosed volumes (used by the unit tests and the benchmark).
#pragma once
#include <cmath>
#include <functional>

#include "pectus/vol/thoracic_volume.h"

namespace pectus::vol::testing {

constexpr double kPi = 3.14159265358979323846;

/// rib-like mask on (theta, z): tilted bands (anterior end lower, like ribs) with gaps between them,
/// plus an always-present sternum strip (theta = pi/2, +y) and spine strip (theta = 3pi/2, -y)
struct RibMask {
  double pitch = 24, ribFraction = 0.6, tilt = 30, stripHalfAngle = 0.22;
  bool operator()(double th, double z) const {
    const double d1 = std::abs(std::remainder(th - kPi / 2, 2 * kPi)), d2 = std::abs(std::remainder(th + kPi / 2, 2 * kPi));
    if (d1 < stripHalfAngle || d2 < stripHalfAngle) return true;
    const double u = (z + tilt * std::sin(th)) / pitch;
    return u - std::floor(u) < ribFraction;
  }
};

/// A sheet x = rx(th,z) cos th, y = ry(th,z) sin th over th in [0,2pi), z in [z0,z1], nth x nz cells,
/// keeping the cells whose centre passes `keep`; appended to s.
inline void addSheet(Soup& s, int nth, int nz, double z0, double z1,
                     const std::function<Eigen::Vector3d(double, double)>& point,
                     const std::function<bool(double, double)>& keep) {
  const int base = int(s.V.size());
  for (int i = 0; i <= nz; ++i)
    for (int j = 0; j < nth; ++j) s.V.push_back(point(2 * kPi * j / nth, z0 + (z1 - z0) * i / nz));
  auto id = [&](int i, int j) { return base + i * nth + (j % nth); };
  for (int i = 0; i < nz; ++i)
    for (int j = 0; j < nth; ++j) {
      const double th = 2 * kPi * (j + 0.5) / nth, z = z0 + (z1 - z0) * (i + 0.5) / nz;
      if (keep && !keep(th, z)) continue;
      s.F.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      s.F.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
}

/// Elliptic cylinder cage: inner sheet (a, b) and outer sheet (a+t, b+t), both cut into rib bands
inline Soup bandedCylinder(double a, double b, double t, double z0, double z1, int nth, int nz, RibMask mask = {}) {
  Soup s;
  for (double off : {0.0, t})
    addSheet(s, nth, nz, z0, z1,
             [&](double th, double z) { return Eigen::Vector3d((a + off) * std::cos(th), (b + off) * std::sin(th), z); },
             mask);
  return s;
}

/// Ellipsoid sheets (semi-axes a, b, c, and a+t, b+t, c+t) cut into rib bands, for |z| <= zcut
inline Soup bandedEllipsoid(double a, double b, double c, double t, double zcut, int nth, int nz, RibMask mask = {}) {
  Soup s;
  for (double off : {0.0, t}) {
    const double A = a + off, Bv = b + off, C = c + off;
    addSheet(s, nth, nz, -zcut, zcut,
             [&](double th, double z) {
               const double f = std::sqrt(std::max(0.0, 1 - z * z / (C * C)));
               return Eigen::Vector3d(A * f * std::cos(th), Bv * f * std::sin(th), z);
             },
             mask);
  }
  return s;
}

/// Closed ellipsoid (UV sphere, outward oriented)
inline Soup closedEllipsoid(double a, double b, double c, int nth, int nph) {
  Soup s;
  s.V.push_back({0, 0, -c});
  for (int i = 1; i < nph; ++i) {
    const double ph = -kPi / 2 + kPi * i / nph;
    for (int j = 0; j < nth; ++j) {
      const double th = 2 * kPi * j / nth;
      s.V.push_back({a * std::cos(ph) * std::cos(th), b * std::cos(ph) * std::sin(th), c * std::sin(ph)});
    }
  }
  s.V.push_back({0, 0, c});
  const int top = int(s.V.size()) - 1;
  auto id = [&](int i, int j) { return 1 + (i - 1) * nth + (j % nth); };
  for (int j = 0; j < nth; ++j) s.F.push_back({0, id(1, j + 1), id(1, j)});
  for (int i = 1; i + 1 < nph; ++i)
    for (int j = 0; j < nth; ++j) {
      s.F.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      s.F.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
  for (int j = 0; j < nth; ++j) s.F.push_back({top, id(nph - 1, j), id(nph - 1, j + 1)});
  return s;
}

/// exact volume of the ellipsoid (a, b, c) between the planes z1 < z2
inline double ellipsoidSegmentVolume(double a, double b, double c, double z1, double z2) {
  return kPi * a * b * ((z2 - z1) - (z2 * z2 * z2 - z1 * z1 * z1) / (3 * c * c));
}

}  // namespace pectus::vol::testing
