// Internal to the patient core: a triangle soup (points + index triples) and the operations the
// preparation steps apply to it. CGAL stays inside soup.cpp.
#pragma once
#include <array>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "pectus/cmesh.h"
#include "pectus/surface_cmesh.h"

namespace pectus::patient {

/// The cores' surface type (pectus/surface.h)
using Soup = pectus::Surface;

/// What the patient core takes of a layer (surfaceOf(m, kFiniteFaces)): its live faces, those touching a
/// non-finite vertex dropped, and the vertices they use
inline const SurfaceOf kFiniteFaces{SurfaceOf::Vertices::UsedByFaces, true, {}};
/// Vertices at exactly the same position merged, faces repeating a vertex and unused vertices dropped
void weld(Soup& s);
void append(Soup& to, const Soup& s);
/// connected pieces (faces sharing a vertex)
std::vector<Soup> components(const Soup& s);
double area(const Soup& s);
/// |enclosed volume| (mm^3); for an open piece, the volume of the cone from its centroid
double volume(const Soup& s);
Eigen::Vector3d centroid(const Soup& s);  ///< area-weighted
/// p -> scale * R p + t, the faces flipped when the map mirrors (det R < 0)
void transform(Soup& s, const Eigen::Matrix3d& R, const Eigen::Vector3d& t);

/// Removes faces with the same three vertices as an earlier face; returns how many
int removeDuplicateFaces(Soup& s);

/// Collapses the edges shorter than minLength, the shortest first, each to its midpoint (CGAL's edge
/// collapse: Edge_length_cost, Midpoint_placement, Bounded_normal_change_filter), keeping the topology. A closed
/// 2-manifold soup only; returns how many edges were collapsed: 0 and s unchanged when the soup is not one.
/// Where the result would intersect itself, the collapse is done again from s with the edges near the
/// crossing kept (their number in keptEdges); -1 and s unchanged when a few such attempts still cross.
int collapseShortEdges(Soup& s, double minLength, int* keptEdges = nullptr);

/// Why the soup is not a closed, 2-manifold, self-intersection-free surface ("" when it is)
std::string defects(const Soup& s);

}  // namespace pectus::patient
