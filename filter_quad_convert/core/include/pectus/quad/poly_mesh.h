// A small host-free polygon mesh (triangles and quads) for the quad conversion and the mesh structure
// operators, and its exchange with MeshLab's CMeshO (a quad = two triangles sharing a faux edge).
#pragma once
#include <array>
#include <string>
#include <vector>

#include "pectus/cmesh.h"
#include "pectus/quality.h"

namespace pectus::quad {

/// One element: nv = 3 or 4 vertices in boundary order. A quad is stored in MeshLab as the two
/// triangles (v0,v1,v2) and (v0,v2,v3): its faux diagonal is v0-v2.
struct Poly {
  int nv = 3;
  std::array<int, 4> v{-1, -1, -1, -1};
};

struct PolyMesh {
  std::vector<Vec3> V;
  std::vector<Poly> F;
  std::size_t quads() const;
  std::size_t triangles() const { return F.size() - quads(); }
};

/// alpha for a triangle, Knupp's beta (own normal, pectus::quadBeta) for a quad
double polyQuality(const PolyMesh& m, const Poly& p);

struct PolyStats {
  std::size_t quads = 0, triangles = 0;
  std::size_t invalidQuads = 0;   ///< beta <= 0
  double quadPercent = 0;         ///< quads / elements * 100
  QualityStats beta;              ///< over quads
  QualityStats alpha;             ///< over triangles
  std::vector<std::size_t> valence;  ///< histogram of interior-node valence (index = valence, capped at 12)
  std::string summary() const;
};
PolyStats polyStats(const PolyMesh& m);

/// number of elements around each vertex, and whether each vertex is on the boundary
void valences(const PolyMesh& m, std::vector<int>& valence, std::vector<char>& boundary);

/// Live vertices and faces of `m` (elements from pectus::buildElements: faux-edge pairs become quads
/// when `quads`); `vertexIndex` receives the index in m.vert of every PolyMesh vertex.
PolyMesh fromCMesh(const CMeshO& m, bool quads, std::vector<int>* vertexIndex = nullptr);
/// Replaces the content of `m`: triangles as faces, quads as two faces (v0,v1,v2),(v0,v2,v3) with the
/// shared edge v0-v2 faux in both (what vcg::tri::PolygonSupport and MeshLab's OFF importer produce).
void toCMesh(const PolyMesh& p, CMeshO& m);

/// Input checks of the cores (a direct caller has no MeshLab layer check before it).
/// Throws InputError naming the first vertex with a NaN or infinite coordinate, used by an element or not (the
/// conversion keeps every vertex, so an unused one would go through into its output).
void requireFiniteVertices(const std::vector<Vec3>& V);
/// Throws TopologyError unless element `index` (`kind`: "triangle", "element") has `nv` vertex indices in
/// [0, vertices) and no vertex twice.
void requireElementIndices(const char* kind, std::size_t index, const int* v, int nv, std::size_t vertices);
/// Both checks over a polygon mesh, and every element a triangle or a quad (else TopologyError).
void requirePolyMesh(const PolyMesh& m);

/// Rotates a quad so its faux diagonal v0-v2 is the one whose two triangles have the larger minimum alpha.
void chooseDiagonal(const PolyMesh& m, Poly& q);

}  // namespace pectus::quad
