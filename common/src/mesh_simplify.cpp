#include "pectus/mesh_simplify.h"

#include <stdexcept>
#include <string>

#include <vcg/complex/append.h>

#include "pectus/errors.h"
#include "pectus/surface_cmesh.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <cstdlib>
#include <unordered_map>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <vcg/complex/algorithms/local_optimization.h>
#include <vcg/complex/algorithms/local_optimization/tri_edge_collapse_quadric.h>
#include <vcg/complex/algorithms/clean.h>
#include <vcg/complex/algorithms/update/topology.h>
#include <vcg/complex/algorithms/update/normal.h>
#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/flag.h>
#include <vcg/container/simple_temporary_data.h>

namespace pectus {
namespace {
using QuadricTemp = vcg::SimpleTempData<CMeshO::VertContainer, vcg::math::Quadric<double>>;
class QHelper {
 public:
  static void Init() {}
  static vcg::math::Quadric<double>& Qd(CVertexO& v) { return TD()[v]; }
  static vcg::math::Quadric<double>& Qd(CVertexO* v) { return TD()[*v]; }
  static CVertexO::ScalarType W(CVertexO*) { return 1.0; }
  static CVertexO::ScalarType W(CVertexO&) { return 1.0; }
  static void Merge(CVertexO&, CVertexO const&) {}
  static QuadricTemp*& TDp() { static QuadricTemp* td = nullptr; return td; }
  static QuadricTemp& TD() { return *TDp(); }
};

// Keeps the decimated surface embedded: a collapse is refused when one of the triangles it moves would
// cross a face of the mesh (or another moved triangle) other than along a shared edge or vertex. The pair
// test is the one of CGAL's self_intersections (exact predicates): shared edge -> coplanar overlap, shared
// vertex -> an opposite edge through the other triangle, else triangle-triangle. Faces are found through
// a uniform grid of their bounding boxes; a face moved by a collapse is added to its new cells (stale
// entries are skipped by a bounding-box test on the current geometry).
class EmbeddingGuard {
 public:
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  EmbeddingGuard(CMeshO& m, double cell, std::vector<vcg::Box3<Scalarm>> regions) : cell_(cell), regions_(std::move(regions)) {
    for (auto& b : regions_) b.Offset(Scalarm(2 * cell));  // faces that can meet a guarded collapse
    for (auto& f : m.face)
      if (!f.IsD()) insert(&f);
  }
  void insert(CFaceO* f) {
    const auto b = box(f->P(0), f->P(1), f->P(2));
    if (!regions_.empty() && std::none_of(regions_.begin(), regions_.end(), [&](const auto& r) { return r.Collide(b); })) return;
    forCells(b, [&](std::vector<CFaceO*>& c) {
      c.erase(std::remove_if(c.begin(), c.end(), [](CFaceO* g) { return g->IsD(); }), c.end());
      if (std::find(c.begin(), c.end(), f) == c.end()) c.push_back(f);
    });
  }
  void moved(CVertexO* v) {
    for (vcg::face::VFIterator<CFaceO> vf(v); !vf.End(); ++vf) insert(vf.F());
  }
  /// would collapsing v0 into v1 at position np keep the surface free of self-intersections?
  bool collapseOk(CVertexO* v0, CVertexO* v1, const Point3m& np) {
    if (!regions_.empty() && std::none_of(regions_.begin(), regions_.end(), [&](const auto& r) {
          return r.IsIn(v0->P()) || r.IsIn(v1->P()) || r.IsIn(np);
        }))
      return true;
    struct Tri { CVertexO* v[3]; K::Point_3 p[3]; CFaceO* f; };
    auto sub = [&](CVertexO* v) { return v == v0 ? v1 : v; };
    auto pos = [&](CVertexO* v) { return v == v0 || v == v1 ? np : v->P(); };
    std::vector<CFaceO*> star;
    for (CVertexO* v : {v0, v1})
      for (vcg::face::VFIterator<CFaceO> vf(v); !vf.End(); ++vf)
        if (!vf.F()->IsD()) star.push_back(vf.F());
    std::sort(star.begin(), star.end());
    star.erase(std::unique(star.begin(), star.end()), star.end());
    std::vector<Tri> moved;
    for (CFaceO* f : star) {
      Tri t{};
      int hasBoth = 0;
      for (int k = 0; k < 3; ++k) {
        hasBoth += f->V(k) == v0 || f->V(k) == v1;
        t.v[k] = sub(f->V(k));
        const Point3m q = pos(f->V(k));
        t.p[k] = K::Point_3(q[0], q[1], q[2]);
      }
      if (hasBoth == 2) continue;  // removed by the collapse
      if (CGAL::collinear(t.p[0], t.p[1], t.p[2])) return false;
      t.f = f;
      moved.push_back(t);
    }
    for (std::size_t i = 0; i < moved.size(); ++i)
      for (std::size_t j = i + 1; j < moved.size(); ++j)
        if (cross(moved[i].v, moved[i].p, moved[j].v, moved[j].p)) return false;
    for (const Tri& t : moved) {
      const auto b = box(pos(t.f->V(0)), pos(t.f->V(1)), pos(t.f->V(2)));
      cand_.clear();
      forCells(b, [&](std::vector<CFaceO*>& c) {
        for (CFaceO* g : c)
          if (!g->IsD() && b.Collide(box(g->P(0), g->P(1), g->P(2))) && !std::binary_search(star.begin(), star.end(), g))
            cand_.push_back(g);
      });
      std::sort(cand_.begin(), cand_.end());
      cand_.erase(std::unique(cand_.begin(), cand_.end()), cand_.end());
      for (CFaceO* g : cand_) {
        CVertexO* gv[3] = {g->V(0), g->V(1), g->V(2)};
        K::Point_3 gp[3];
        for (int k = 0; k < 3; ++k) gp[k] = K::Point_3(g->P(k)[0], g->P(k)[1], g->P(k)[2]);
        if (!CGAL::collinear(gp[0], gp[1], gp[2]) && cross(t.v, t.p, gv, gp)) return false;
      }
    }
    return true;
  }

 private:
  static vcg::Box3<Scalarm> box(const Point3m& a, const Point3m& b, const Point3m& c) {
    vcg::Box3<Scalarm> x;
    x.Add(a), x.Add(b), x.Add(c);
    return x;
  }
  template <class F>
  void forCells(const vcg::Box3<Scalarm>& b, F&& fn) {
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = int(std::floor(b.min[a] / cell_)), hi[a] = int(std::floor(b.max[a] / cell_));
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x)
          fn(cells_[(std::uint64_t(std::uint32_t(z) & 0x1fffff) << 42) | (std::uint64_t(std::uint32_t(y) & 0x1fffff) << 21) |
                    std::uint64_t(std::uint32_t(x) & 0x1fffff)]);
  }
  // CGAL's test for two faces of one surface (PMP::self_intersections' do_faces_intersect)
  static bool cross(CVertexO* const av[3], const K::Point_3 ap[3], CVertexO* const bv[3], const K::Point_3 bp[3]) {
    int shared = 0, ia = -1, ib = -1, ia2 = -1, ib2 = -1;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (av[i] == bv[j]) {
          if (shared == 0) ia = i, ib = j; else ia2 = i, ib2 = j;
          ++shared;
        }
    if (shared == 3) return true;  // the same triangle twice
    if (shared == 2) {             // overlap in their common plane on the same side of the shared edge
      const K::Point_3& x = ap[3 - ia - ia2];
      const K::Point_3& y = bp[3 - ib - ib2];
      return CGAL::coplanar(ap[ia], ap[ia2], x, y) && CGAL::coplanar_orientation(ap[ia], ap[ia2], x, y) == CGAL::POSITIVE;
    }
    const K::Triangle_3 ta(ap[0], ap[1], ap[2]), tb(bp[0], bp[1], bp[2]);
    if (shared == 1)
      return CGAL::do_intersect(ta, K::Segment_3(bp[(ib + 1) % 3], bp[(ib + 2) % 3])) ||
             CGAL::do_intersect(tb, K::Segment_3(ap[(ia + 1) % 3], ap[(ia + 2) % 3]));
    return CGAL::do_intersect(ta, tb);
  }
  double cell_;
  std::vector<vcg::Box3<Scalarm>> regions_;  // guarded regions (grown by 2 cells); empty: everywhere
  std::vector<CFaceO*> cand_;
  std::unordered_map<std::uint64_t, std::vector<CFaceO*>> cells_;
};
EmbeddingGuard*& guard() { static EmbeddingGuard* g = nullptr; return g; }

using VertexPair = vcg::tri::BasicVertexPair<CVertexO>;
class Collapse : public vcg::tri::TriEdgeCollapseQuadric<CMeshO, VertexPair, Collapse, QHelper> {
 public:
  using TECQ = vcg::tri::TriEdgeCollapseQuadric<CMeshO, VertexPair, Collapse, QHelper>;
  Collapse(const VertexPair& p, int i, vcg::BaseParameterClass* pp) : TECQ(p, i, pp) {}
  bool IsFeasible(vcg::BaseParameterClass* pp) override {
    return TECQ::IsFeasible(pp) && (!guard() || guard()->collapseOk(this->pos.V(0), this->pos.V(1), this->optimalPos));
  }
  void Execute(CMeshO& m, vcg::BaseParameterClass* pp) override {
    CVertexO* kept = this->pos.V(1);
    TECQ::Execute(m, pp);
    if (guard()) guard()->moved(kept);
  }

  // The start of the decimation, the same on every MeshLab release: vcglib's own Init weighs each face's
  // plane by (twice) its area squared in the vcglib of MeshLab 2020.09 and by the area once in 2025.07, so
  // the collapses, and the generated cage, would differ by release (the rest of the collapse is the same
  // code in both). This is 2020.09's Init for the options used here: no boundary to preserve, optimal
  // placement, so the collapses are symmetric.
  static void Init(CMeshO& m, vcg::LocalOptimization<CMeshO>::HeapType& heap, vcg::BaseParameterClass* bp) {
    auto* pp = static_cast<vcg::tri::TriEdgeCollapseQuadricParameter*>(bp);
    pp->CosineThr = std::cos(pp->NormalThrRad);
    heap.clear();
    vcg::tri::UpdateTopology<CMeshO>::VertexFace(m);
    vcg::tri::UpdateFlags<CMeshO>::FaceBorderFromVF(m);
    initQuadrics(m, *pp);
    pushEveryEdge(m, heap, bp);
  }

 private:
  static void initQuadrics(CMeshO& m, vcg::tri::TriEdgeCollapseQuadricParameter& pp) {
    for (auto& v : m.vert)
      if (!v.IsD() && v.IsW()) QHelper::Qd(v).SetZero();
    for (auto& f : m.face) {
      if (f.IsD() || !f.IsR() || !f.V(0)->IsR() || !f.V(1)->IsR() || !f.V(2)->IsR()) continue;
      vcg::Plane3<Scalarm, false> plane;  // not normalised: the quadric weighs by the area squared
      plane.SetDirection((f.V(1)->cP() - f.V(0)->cP()) ^ (f.V(2)->cP() - f.V(0)->cP()));
      plane.SetOffset(plane.Direction().dot(f.V(0)->cP()));
      vcg::math::Quadric<double> q;
      q.ByPlane(plane);
      for (int j = 0; j < 3; ++j)
        if (f.V(j)->IsW()) QHelper::Qd(f.V(j)) += q;
      for (int j = 0; j < 3; ++j) {
        if (!f.IsB(j)) continue;  // an open edge: the plane through it, square to the face, amplified
        vcg::Plane3<Scalarm, false> border;
        border.SetDirection(plane.Direction() ^ (f.V1(j)->cP() - f.V(j)->cP()).normalized());
        border.SetDirection(border.Direction() * Scalarm(pp.BoundaryQuadricWeight));
        border.SetOffset(border.Direction().dot(f.V(j)->cP()));
        vcg::math::Quadric<double> bq;
        bq.ByPlane(border);
        if (f.V(j)->IsW()) QHelper::Qd(f.V(j)) += bq;
        if (f.V1(j)->IsW()) QHelper::Qd(f.V1(j)) += bq;
      }
    }
    if (pp.ScaleIndependent) {
      vcg::tri::UpdateBounding<CMeshO>::Box(m);
      pp.ScaleFactor = 1e8 * std::pow(1.0 / m.bbox.Diag(), 6);
    }
  }
  static void pushEveryEdge(CMeshO& m, vcg::LocalOptimization<CMeshO>::HeapType& heap, vcg::BaseParameterClass* bp) {
    using Mark = vcg::tri::TriEdgeCollapse<CMeshO, VertexPair, Collapse>;
    for (auto& v : m.vert) {
      if (v.IsD() || !v.IsRW()) continue;
      vcg::face::VFIterator<CFaceO> x;
      for (x.F() = v.VFp(), x.I() = v.VFi(); x.F() != nullptr; ++x) x.V1()->ClearV(), x.V2()->ClearV();
      for (x.F() = v.VFp(), x.I() = v.VFi(); x.F() != nullptr; ++x)
        for (CVertexO* w : {x.V1(), x.V2()})
          if (x.V0() < w && w->IsRW() && !w->IsV()) {
            w->SetV();
            heap.push_back(vcg::LocalOptimization<CMeshO>::HeapElem(new Collapse(VertexPair(x.V0(), w), Mark::GlobalMark(), bp)));
          }
    }
  }
};
}  // namespace

void decimateQuadric(CMeshO& m, int targetFaces, double embeddingCell, const std::vector<vcg::Box3<Scalarm>>& guarded) {
  if (m.fn <= targetFaces) return;
  if (!m.vert.IsVFAdjacencyEnabled()) m.vert.EnableVFAdjacency();
  if (!m.face.IsVFAdjacencyEnabled()) m.face.EnableVFAdjacency();
  if (!m.vert.IsMarkEnabled()) m.vert.EnableMark();
  vcg::tri::UpdateTopology<CMeshO>::VertexFace(m);
  vcg::tri::UpdateNormal<CMeshO>::PerFaceNormalized(m);
  vcg::tri::TriEdgeCollapseQuadricParameter pp;
  pp.PreserveTopology = true;
  pp.NormalCheck = true;
  pp.NormalThrRad = M_PI / 6;
  pp.QualityCheck = true;
  pp.QualityThr = 0.3;
  pp.HardQualityCheck = true;
  pp.HardQualityThr = 0.1;
  pp.OptimalPlacement = true;
  pp.QualityQuadric = false;
  pp.QualityWeight = false;  // Init above has no per-vertex quality weight

  {
    vcg::math::Quadric<double> zero;
    zero.SetZero();
    QuadricTemp td(m.vert, zero);
    QHelper::TDp() = &td;
    std::unique_ptr<EmbeddingGuard> g;
    if (embeddingCell > 0) g = std::make_unique<EmbeddingGuard>(m, embeddingCell, guarded);
    guard() = g.get();
    vcg::LocalOptimization<CMeshO> session(m, &pp);
    session.Init<Collapse>();
    session.SetTargetSimplices(targetFaces);
    session.DoOptimization();
    session.Finalize<Collapse>();
    QHelper::TDp() = nullptr;
    guard() = nullptr;
  }
  vcg::tri::Allocator<CMeshO>::CompactEveryVector(m);
  m.face.DisableVFAdjacency();
  m.vert.DisableVFAdjacency();
}

int decimateEmbedded(CMeshO& m, int targetFaces, double edgeLength) {
  CMeshO raw;
  vcg::tri::Append<CMeshO, CMeshO>::MeshCopy(raw, m);
  std::vector<vcg::Box3<Scalarm>> guarded;
  constexpr int kAttempts = 4;
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    if (attempt > 0) {
      m.Clear();
      vcg::tri::Append<CMeshO, CMeshO>::MeshCopy(m, raw);
    }
    const bool everywhere = attempt == kAttempts - 1;
    decimateQuadric(m, targetFaces, attempt > 0 ? 0.5 * edgeLength : 0.0, everywhere ? std::vector<vcg::Box3<Scalarm>>{} : guarded);
    const std::vector<int> si = selfIntersectingFaces(m);
    if (si.empty()) return attempt;
    if (everywhere)
      throw InternalError("the decimated surface intersects itself (" + std::to_string(si.size()) +
                          " faces); use another edge length");
    for (int f : si) {
      vcg::Box3<Scalarm> b;
      for (int k = 0; k < 3; ++k) b.Add(m.face[std::size_t(f)].P(k));
      b.Offset(Scalarm(2 * edgeLength));
      guarded.push_back(b);
    }
  }
  return kAttempts - 1;
}

}  // namespace pectus
