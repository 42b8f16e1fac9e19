// Internal to the patient core: a structure's solid on a regular grid, from any triangle surface.
//
// The solid is the set of grid points that no path from outside can reach without crossing a face: the surface is
// rasterised as the grid edges it crosses, and the outside is flooded through the others. What a real export
// holds cannot stop that: duplicate faces and self-intersections cross the same edges; a marrow cavity's shell
// nested inside a bone lies where the flood never comes, so the bone is solid; a sliver or a sheet encloses no
// point; pieces that touch or overlap are one solid. A surface with holes would let the flood in, so every hole is
// capped first by a fan of triangles from the centre of its rim, which spans the rim however it winds. Every step is a scan in a fixed order: the same input gives the
// same solid, bit for bit, on any machine and thread count.
#pragma once
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Dense>

#include "pectus/patient/soup.h"

namespace pectus::patient {

/// Points of an index box: n[0] * n[1] * n[2], the first index fastest
struct Box3i {
  std::array<int, 3> lo{0, 0, 0}, n{0, 0, 0};
  std::size_t size() const { return std::size_t(n[0]) * std::size_t(n[1]) * std::size_t(n[2]); }
  std::size_t index(int a, int b, int c) const {  ///< local indices a, b, c
    return std::size_t(a) + std::size_t(n[0]) * (std::size_t(b) + std::size_t(n[1]) * std::size_t(c));
  }
  bool contains(int i, int j, int k) const {  ///< global indices
    return i >= lo[0] && j >= lo[1] && k >= lo[2] && i < lo[0] + n[0] && j < lo[1] + n[1] && k < lo[2] + n[2];
  }
};

/// A regular grid of points origin + h * (i, j, k), in mm
struct Grid {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double h = 1;
  Box3i box;  ///< the points of the grid (box.lo = 0)
  Eigen::Vector3d point(double i, double j, double k) const { return origin + h * Eigen::Vector3d(i, j, k); }
};

/// A solid on a box of a grid's points (global indices box.lo .. box.lo + box.n - 1)
struct Solid {
  Box3i box;
  std::vector<std::uint8_t> in;  ///< per point of the box: 1 inside
  /// the grid edges the surface crosses, key 3 * (local index of the point) + axis for the edge from the point to
  /// its +axis neighbour: the first and the last crossing along the edge, as a share 0..1 of it
  std::unordered_map<std::uint64_t, std::array<float, 2>> cross;
  int duplicates = 0;  ///< faces written twice (ignored)
  int capped = 0;      ///< holes capped (rims of edges in an odd number of faces)
  std::size_t count() const;  ///< inside points
  bool inside(int i, int j, int k) const { return box.contains(i, j, k) && in[box.index(i - box.lo[0], j - box.lo[1], k - box.lo[2])]; }
  /// The share 0..1 along the grid edge from global point (i, j, k) to its +axis neighbour where the surface is
  /// left going from the inside end to the outside one (the crossing nearest the outside end); 0.5 where the
  /// surface does not cross the edge (a sealed hole, a cut)
  double exit(int i, int j, int k, int axis, bool insideAtStart) const;
};

/// The solid bounded by s on grid g (the box of s's points, two grid steps wider on each side), its holes capped
Solid solidify(const Soup& s, const Grid& g);

/// 6-connected components of the points with mask != 0 in a box of n points: comp per point (0 none, else
/// 1 + component, numbered in scan order), the number of points of each
std::vector<std::size_t> components6(const std::array<int, 3>& n, const std::vector<std::uint8_t>& mask,
                                     std::vector<std::int32_t>& comp);

/// The squared distance (in grid steps) from each point of a box of n points to the nearest point with
/// set != 0 (the exact Euclidean distance transform; 1e20 where the set is empty)
std::vector<float> squaredDistance(const std::array<int, 3>& n, const std::vector<std::uint8_t>& set);

}  // namespace pectus::patient
