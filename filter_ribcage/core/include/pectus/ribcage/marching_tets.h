// Sparse marching tetrahedra on a regular grid (Kuhn decomposition: 6 tets per cube sharing the main
// diagonal, consistent across cubes). The output is the zero set of the piecewise-linear interpolant
// of f: a closed, oriented (outward = towards f > 0), 2-manifold, non-self-intersecting surface as
// long as no grid value is exactly 0 (values are pushed away from 0 by a tiny epsilon).
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Dense>

namespace pectus::ribcage {

struct SparseGrid {
  Eigen::Vector3d origin;       ///< position of grid point (0,0,0)
  double h = 1;                 ///< spacing
  std::array<int, 3> points{};  ///< grid points per axis
  int block = 8;                ///< cubes per block edge
  std::vector<char> active;     ///< per block (x fastest); inactive blocks are taken as f > 0 everywhere
  std::array<int, 3> blocks() const {
    return {(points[0] - 2) / block + 1, (points[1] - 2) / block + 1, (points[2] - 2) / block + 1};
  }
};

struct TriSoup {
  std::vector<Eigen::Vector3d> V;
  std::vector<std::array<int, 3>> F;
};

/// f(p) must be deterministic; it is called on grid points of active blocks only (in parallel).
TriSoup marchingTets(const SparseGrid& g, const std::function<double(const Eigen::Vector3d&)>& f);

}  // namespace pectus::ribcage
