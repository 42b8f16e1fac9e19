// Finite elements (triangles and quads) of a MeshLab mesh. MeshLab stores a quad as two triangles
// sharing an edge with the faux flag set (vcg::tri::PolygonSupport). This groups faces into elements.
#pragma once
#include <array>
#include <vector>

#include "pectus/cmesh.h"

namespace pectus {

struct Element {
  int nv = 3;                      ///< 3 or 4
  std::array<int, 4> v{-1, -1, -1, -1};  ///< vertex indices in boundary order (counter-clockwise as the faces)
  std::array<int, 2> face{-1, -1};       ///< the one or two triangle faces of the element
};

enum class ElementKind { Triangles, Quads };

struct ElementMesh {
  std::vector<Element> elements;
  std::vector<int> faceToElement;  ///< per face index (deleted faces: -1)
  std::size_t quads() const;
  std::size_t triangles() const;
};

/// True if any live face has a faux edge (i.e. the mesh holds polygons the MeshLab way).
bool hasFauxEdges(const CMeshO& m);

/// Triangles: one element per live face, faux flags ignored.
/// Quads: two faces joined across a faux edge make a quad; faces with no faux edge stay triangles.
/// Throws TopologyError when the faux edges do not describe quads (a face with two faux edges, i.e. a
/// polygon of more than four sides; a faux edge on the boundary or shared by more than two faces).
ElementMesh buildElements(const CMeshO& m, ElementKind kind);

}  // namespace pectus
