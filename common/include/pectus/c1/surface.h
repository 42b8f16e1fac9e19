// C1 surface reconstruction of thesis chapter 3: vertex gradients by local estimation (eqs. 3-1..3-5)
// and Goodman-Said cubic Bezier triangular patches with the rational blend of the three b111
// (eqs. 3-6..3-16), for scalar height fields and for 3D triangle meshes (closed surfaces included).
//
// The patch is vector valued: every coordinate is one Goodman-Said interpolant over the mesh triangle.
// What a vertex contributes is a linear "derivative map" T_v(d) = d - (n_v.d)/(n_v.k) k applied to the
// triangle's edge vectors d (control point b210 = V1 + T_1(V2-V1)/3, eq. 3-10 per coordinate):
//  - Frame::HeightField (k = a fixed axis, e.g. z): T_v(d) = (d_xy, g_v.d_xy), i.e. the thesis' scalar
//    interpolant of the height over the plane orthogonal to k, the x,y coordinates reproduced linearly.
//    C1 across edges (the h_i of eq. 3-12 are taken in that plane) and exact for quadratic heights with
//    exact gradients.
//  - Frame::VertexNormal (k = n_v, orthogonal projection onto the vertex tangent plane): for any
//    oriented 2-manifold (closed surfaces: bone, rib cage). Interpolates the vertices and their tangent
//    planes, C0 across edges exactly (edge curves depend only on the edge's two vertices), tangent plane
//    continuous at the vertices, and the normal jump across an edge shrinks with the mesh size (it is not
//    exactly G1 away from the vertices). h_i from the 3D triangle itself.
// Vertex normals (gradients) come from
//  - GradientMethod::MinimumCurvature (default): HeightField: one global estimate, the gradients that
//    minimize the curvature energy of the edge network (Nielson 1983, the estimate behind scipy's
//    Clough-Tocher): sum over edges of L^-1/2 * integral of p''(s)^2 along the edge, p the cubic Hermite
//    curve of the end values and end directional derivatives; a sparse SPD system (Eigen LDLT), linear
//    data reproduced exactly. The L^-1/2 edge weight (Nielson: 1) favours short edges; it is chosen on
//    Table 3-1's sets (36-point grid, Franke 33/100) and checked on other jittered grids and functions.
//    VertexNormal frame: the per-vertex QuadraticFit below (no global height to minimize over).
//  - GradientMethod::QuadraticFit: weighted least-squares fit of a quadratic height over the 2-ring (3-ring
//    at corners), weights 1/(0.01+r^2)^2 with r in 1-ring units, in the vertex frame; per vertex.
//  - GradientMethod::InverseArea (thesis eqs. 3-1/3-2: inverse-area weighted facet gradients, boundary
//    extrapolation 3-2), or are given.
//
// Bad input (pectus::InputError): non-finite coordinates, a HeightField mesh that folds over the axis; its
// pectus::TopologyError: faces with invalid indices, duplicate faces, edges with 3+ faces, non-manifold
// vertices (two fans glued at a vertex).
// Documented fallbacks (never NaN): zero-area triangles are skipped in the gradient estimation and get
// h_i = 1/2 on a zero-length edge; a vertex whose frame cannot be built (all its faces degenerate) gets
// the identity derivative map (edges leave it straight) and counts in stats().flatVertices; isolated
// vertices are ignored (normal = k or (0,0,1)), and dropped by refine().
#pragma once
#include <Eigen/Dense>

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "pectus/param_range.h"
#include "pectus/surface.h"

namespace pectus::c1 {

/// the k of C1Surface::refine (each triangle split k x k); the refinement filter declares it with this range
inline constexpr ParamRange kSubdivisionsRange{1, 32};

using Vec3 = Eigen::Vector3d;
using Vec2 = Eigen::Vector2d;

using TriMesh = pectus::Surface;  ///< the cores' triangle surface (pectus/surface.h)

enum class GradientMethod {
  QuadraticFit,      ///< per vertex: weighted LSQ quadratic over the 2-ring in the vertex frame
  InverseArea,       ///< thesis eqs. 3-1 (interior) and 3-2 (boundary): inverse-area weighted facet gradients
  MinimumCurvature,  ///< default: HeightField global minimum-curvature estimate; VertexNormal: QuadraticFit
};

enum class Frame {
  VertexNormal,  ///< 3D surfaces: frame of the area-weighted averaged normal per vertex
  HeightField,   ///< z = f(x,y) along Options::axis: the thesis' scalar interpolant, exactly C1
};

enum class Blend {
  GoodmanSaid,  ///< eq. 3-16: rational blend of the three b111 (C1)
  PlainCubic,   ///< one b111 = mean of the three (C0 cubic; for comparison and tests only)
};

struct Options {
  GradientMethod gradient = GradientMethod::MinimumCurvature;
  Frame frame = Frame::VertexNormal;
  Vec3 axis{0, 0, 1};  ///< the height axis of Frame::HeightField
  Blend blend = Blend::GoodmanSaid;
};

struct Stats {
  std::size_t faces = 0, vertices = 0, isolatedVertices = 0, degenerateFaces = 0;
  std::size_t boundaryVertices = 0, flatVertices = 0;  ///< flat: frame fallback (identity map)
  std::size_t linearFitVertices = 0;  ///< QuadraticFit fell back to a plane fit (too few neighbours)
  bool globalGradients = false;       ///< MinimumCurvature: the global solve was used (else per vertex)
};

/// A point on the surface: patch (face) and barycentric coordinates (u, v, w) of its vertices 0,1,2.
struct SurfacePoint {
  int face = -1;
  Vec3 bary{1, 0, 0};
  Vec3 point{0, 0, 0};
  Vec3 normal{0, 0, 1};  ///< unit normal of the patch there (oriented like the face)
  double distance = 0;   ///< closestPoint(): |query - point|
};

/// Position and first derivatives of a patch with respect to (s, t), where bary = (1-s-t, s, t).
struct PatchJet {
  Vec3 P, Ps, Pt;
  Vec3 normal() const;  ///< normalized Ps x Pt (zero if degenerate)
};

class C1Surface {
 public:
  /// Estimates vertex normals with opt.gradient and builds the patches. Throws InputError (TopologyError
  /// for the mesh's topology; see above).
  explicit C1Surface(TriMesh mesh, const Options& opt = {});
  /// Given unit vertex normals (HeightField: any normal not orthogonal to the axis).
  C1Surface(TriMesh mesh, std::vector<Vec3> normals, const Options& opt);
  ~C1Surface();
  C1Surface(C1Surface&&) noexcept;
  C1Surface& operator=(C1Surface&&) noexcept;

  const TriMesh& mesh() const { return mesh_; }
  const Options& options() const { return opt_; }
  const Stats& stats() const { return stats_; }
  /// unit vertex normals used by the patches (HeightField: (-g, 1)/|(-g,1)| in the axis frame)
  const std::vector<Vec3>& normals() const { return normals_; }
  /// HeightField only: the gradient of the height at every vertex, in the frame (e1, e2) of frameAxes()
  std::vector<Vec2> heightGradients() const;
  /// orthonormal (e1, e2) completing Options::axis to a right-handed frame (HeightField)
  std::pair<Vec3, Vec3> frameAxes() const;

  /// (triangle, barycentric) -> surface point (bary need not be normalized; it is divided by its sum)
  Vec3 eval(int face, const Vec3& bary) const;
  PatchJet jet(int face, const Vec3& bary) const;
  SurfacePoint at(int face, const Vec3& bary) const;
  /// the 10 control points of the cubic part, order b300 b210 b201 b120 b102 b030 b021 b012 b003, and
  /// the three b111^i (i = edge opposite vertex i)
  std::array<Vec3, 12> controlNet(int face) const;

  /// Closest point of the C1 surface to p (spatial grid on the patches' bounding boxes, branch and
  /// bound, projected Newton per candidate patch). Call buildIndex() once before calling it from
  /// several threads; after that it is thread-safe.
  SurfacePoint closestPoint(const Vec3& p) const;
  void buildIndex() const;

  /// An edge of the mesh: vertices a < b and the faces on either side (f1 = -1 on the boundary)
  struct EdgeFaces {
    int a, b, f0, f1;
  };
  /// the mesh's edges, from the topology the patches were built on (ascending (a, b))
  std::vector<EdgeFaces> edges() const;
  /// the topology the patches were built on (checked: closed or with a boundary, manifold)
  const Topology& topology() const { return *topo_; }
  /// per face, the face across local edge l (the edge opposite local vertex l); -1 on the boundary
  std::vector<std::array<int, 3>> faceNeighbours() const;

  /// Each triangle split k x k (k in kSubdivisionsRange, else InputError); new vertices on the patches, edge
  /// vertices shared (conforming output).
  /// Vertex order: the input's referenced vertices (in input order), then edge, then interior vertices.
  /// `normals`, if given, receives the patch normal at every output vertex.
  TriMesh refine(int k, std::vector<Vec3>* normals = nullptr) const;

 private:
  void build(std::vector<Vec3>* givenNormals);
  template <class T> void evalImpl(int face, const T& s, const T& t, Vec3& P, Vec3& Ps, Vec3& Pt) const;
  TriMesh mesh_;
  Options opt_;
  Stats stats_;
  std::vector<Vec3> normals_;
  std::vector<char> flat_;
  std::shared_ptr<const Topology> topo_;
  std::vector<std::array<Vec3, 9>> net_;  ///< per face: 6 edge points + 3 b111
  struct Index;
  mutable std::unique_ptr<Index> index_;
};

/// Volume enclosed by a closed, consistently oriented triangle mesh (divergence theorem).
double enclosedVolume(const TriMesh& m);

/// Vertex gradients of a scalar field over a planar triangulation (thesis eqs. 3-1..3-5, the quadratic fit or
/// the global minimum-curvature estimate).
std::vector<Vec2> estimateGradients2D(const std::vector<Vec2>& xy, const std::vector<double>& f,
                                      const std::vector<std::array<int, 3>>& tris, GradientMethod method);

/// Scalar Goodman-Said interpolant of f over a planar triangulation (HeightField with axis z):
/// value at (x, y) given the triangle that contains it. Gradients: estimated if empty.
class HeightInterpolant {
 public:
  HeightInterpolant(const std::vector<Vec2>& xy, const std::vector<double>& f,
                    const std::vector<std::array<int, 3>>& tris, GradientMethod method,
                    std::vector<Vec2> gradients = {}, Blend blend = Blend::GoodmanSaid);
  /// value in triangle `tri` at (x, y) (barycentric coordinates from the planar triangle)
  double value(int tri, const Vec2& p) const;
  /// value and gradient (df/dx, df/dy)
  double value(int tri, const Vec2& p, Vec2* grad) const;
  const C1Surface& surface() const { return surf_; }
  const std::vector<Vec2>& gradients() const { return grads_; }

 private:
  std::vector<Vec2> xy_;
  std::vector<Vec2> grads_;
  C1Surface surf_;
};

}  // namespace pectus::c1
