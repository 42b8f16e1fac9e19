// Crease detection: which nodes of a triangle mesh lie on a real crease of the surface (an edge of a CAD
// part), as opposed to an edge that is sharp only through the noise of a scanned or CT surface.
// Host-free (Eigen, no Qt).
//
// A single dihedral threshold cannot tell the two apart: on the CGAL femur (a CT bone) the median edge is
// bent by 17 degrees and one edge in seven by more than 60, on the fandisk (a CAD part) nine edges in ten
// are flat and the creases are bent by 20 to 90 degrees. A crease is told from noise by three properties,
// tested in this order:
//   1. sharp across: the edge's dihedral angle (between its two faces' normals) is at least minDihedral
//      and at least edgeProminence times the median dihedral of the faces' four other edges (its "wings";
//      those bent less than minDihedral, if any): the surface is smooth on both sides of a crease, its
//      curvature concentrated on the edge;
//   2. a chain: two sharp edges through a node are linked if each is the other's straightest
//      continuation there, with dihedral angles that differ by at most the factor linkRatio and a turn
//      of at most maxTurn (a spur of noise at a crease node does not break the crease; three creases
//      meeting at a corner turn too much to link);
//   3. a consistent chain: its dihedral varies little along it (standard deviation over mean at most
//      maxVariation), it is sharper than its wings as a whole (mean dihedral over the mean of the wings
//      that are not sharp at least chainProminence) and than the mesh's noise (mean dihedral over the
//      median dihedral of the edges that are not sharp at least noiseProminence), and it is long (at least minChainEdges edges, closed
//      or not), runs from corner to corner (three or more consistent chains and no other sharp edge end
//      at each of its ends), or continues a crease (meets an end of a chain that is a crease by the
//      other rules: the short sides of a CAD part).
// Every node of a crease chain is a crease node; a node where three or more crease edges meet, or where
// an open crease chain ends, is a corner.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "pectus/quality.h"  // Vec3
#include "pectus/surface.h"  // Topology

namespace pectus::smooth {

struct CreaseOptions {
  double minDihedralDeg = 20;    ///< an edge bent less than this is never sharp
  double edgeProminence = 2;     ///< edge dihedral over the median of its wings
  double linkRatio = 1.25;       ///< largest ratio of the dihedral angles of two linked edges
  double maxTurnDeg = 60;        ///< largest turn of a chain at a node
  int minChainEdges = 4;         ///< a chain that does not run from corner to corner needs this many edges
  double maxVariation = 0.4;     ///< largest standard deviation over mean of a chain's dihedral angles
  double chainProminence = 6;    ///< smallest mean dihedral over mean wing of a chain
  double noiseProminence = 12;   ///< smallest mean dihedral of a chain over the mesh's noise (noiseDeg)
};

struct Creases {
  std::vector<char> node;      ///< per vertex: on a crease chain
  std::vector<char> corner;    ///< per vertex: three or more crease edges meet, or an open crease chain ends
  std::vector<std::vector<std::array<int, 2>>> chains;  ///< the crease chains, as edges (vertex pairs)
  std::size_t sharpEdges = 0;     ///< edges that passed step 1
  std::size_t creaseEdges = 0;    ///< edges of the crease chains
  std::size_t rejectedChains = 0; ///< chains of sharp edges taken for noise
  double noiseDeg = 0;            ///< the median dihedral angle of the mesh's inner edges that are not sharp, degrees
  std::size_t creaseNodes() const;
  std::size_t cornerNodes() const;
  /// one line for the Log, e.g. "12 crease chains (192 edges, 186 nodes, 8 corners); 0 of 192 sharp
  /// edges taken for noise" or "no crease: 343 sharp edges, all noise (every node free)"
  std::string summary() const;
};

/// Crease detection on the triangles F over the vertices V. Edges with one face (the boundary) or more than
/// two, and the edges whose key edgeKey(a, b) is in `ignored` (sorted; e.g. the faux edges inside quads),
/// are never sharp. Degenerate faces (no normal) make no edge sharp.
Creases detectCreases(const std::vector<Vec3>& V, const std::vector<std::array<int, 3>>& F,
                      const std::vector<std::uint64_t>& ignored = {}, const CreaseOptions& opt = {});
/// The same on the topology of (V, F) the caller has built already (Topology(Surface{V, F}), e.g. that of
/// the C1 surface on them).
Creases detectCreases(const std::vector<Vec3>& V, const std::vector<std::array<int, 3>>& F, const Topology& topo,
                      const std::vector<std::uint64_t>& ignored = {}, const CreaseOptions& opt = {});

/// the key of the undirected edge a-b, as `ignored` takes it
inline std::uint64_t edgeKey(int a, int b) {
  return (std::uint64_t(std::uint32_t(a < b ? a : b)) << 32) | std::uint32_t(a < b ? b : a);
}

}  // namespace pectus::smooth
