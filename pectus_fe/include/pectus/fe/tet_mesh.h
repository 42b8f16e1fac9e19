// Host-free tetrahedral mesh for the Nuss FE solver (mm). Linear 4-node (TET4) and quadratic 10-node
// (TET10) tetrahedra. Node order is CalculiX/Abaqus C3D4/C3D10 = VTK 10/24:
//   corners 0..3, then mid-edge nodes of edges (0,1) (1,2) (2,0) (0,3) (1,3) (2,3).
#pragma once
#include <array>
#include <functional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace pectus::fe {

struct TetMesh {
  std::vector<Eigen::Vector3d> nodes;
  int order = 1;                       ///< 1: TET4, 2: TET10
  std::vector<std::array<int, 10>> tets;  ///< first 4 (TET4) or 10 (TET10) entries used
  std::vector<int> tissue;             ///< per tet (pectus::Tissue values: 1 bone, 2 cartilage, 3 sternum)

  int nodesPerTet() const { return order == 2 ? 10 : 4; }
  int numTets() const { return static_cast<int>(tets.size()); }
  int numNodes() const { return static_cast<int>(nodes.size()); }
  double tetVolume(int t) const;  ///< signed volume of the corner tet (positive when well oriented)
  Eigen::Vector3d centroid(int t) const {  ///< of the four corners
    const auto& T = tets[t];
    return (nodes[T[0]] + nodes[T[1]] + nodes[T[2]] + nodes[T[3]]) / 4;
  }
};

/// Edges of a tet in the C3D10 mid-node order
constexpr int kTetEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

/// Returns a TET10 mesh: the TET4 mesh with one straight mid-edge node per edge (shared between tets).
TetMesh toQuadratic(const TetMesh& linear);

/// A box [0,lx]x[0,ly]x[0,lz] of nx*ny*nz hexahedra, each split into 6 tets (Kuhn/Freudenthal split,
/// conforming), optionally mapped by `map` (e.g. to a cylinder sector). All tets get `tissue`.
TetMesh structuredBox(double lx, double ly, double lz, int nx, int ny, int nz, int tissue = 1,
                      const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& map = {});

/// Boundary faces (triangles of tets not shared with another tet), corner nodes oriented outwards,
/// plus for TET10 the 3 mid-edge nodes of edges (0,1) (1,2) (2,0) in entries 3..5.
struct BoundaryFace { std::array<int, 6> n; int tet; };
std::vector<BoundaryFace> boundaryFaces(const TetMesh& m);

/// Consistent nodal forces (N) of a pressure p (MPa, positive pushing into the body) on the given
/// boundary faces (flat faces: TET4 1/3 per corner; TET10 0 per corner, 1/3 per mid-edge node).
/// Returned as a per-node force vector (size numNodes).
std::vector<Eigen::Vector3d> pressureLoads(const TetMesh& m, const std::vector<BoundaryFace>& faces, double p);
/// Same for a uniform traction t (force per area, MPa) on the faces.
std::vector<Eigen::Vector3d> tractionLoads(const TetMesh& m, const std::vector<BoundaryFace>& faces,
                                           const Eigen::Vector3d& t);

}  // namespace pectus::fe
