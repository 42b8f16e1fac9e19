#include "mesh_simplify.h"

#include <cstdlib>

#include <vcg/complex/algorithms/local_optimization.h>
#include <vcg/complex/algorithms/local_optimization/tri_edge_collapse_quadric.h>
#include <vcg/complex/algorithms/clean.h>
#include <vcg/complex/algorithms/update/topology.h>
#include <vcg/complex/algorithms/update/normal.h>
#include <vcg/container/simple_temporary_data.h>

namespace pectus::ribcage {
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
using VertexPair = vcg::tri::BasicVertexPair<CVertexO>;
class Collapse : public vcg::tri::TriEdgeCollapseQuadric<CMeshO, VertexPair, Collapse, QHelper> {
 public:
  using TECQ = vcg::tri::TriEdgeCollapseQuadric<CMeshO, VertexPair, Collapse, QHelper>;
  Collapse(const VertexPair& p, int i, vcg::BaseParameterClass* pp) : TECQ(p, i, pp) {}
};
}  // namespace

void decimateQuadric(CMeshO& m, int targetFaces) {
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

  {
    vcg::math::Quadric<double> zero;
    zero.SetZero();
    QuadricTemp td(m.vert, zero);
    QHelper::TDp() = &td;
    vcg::LocalOptimization<CMeshO> session(m, &pp);
    session.Init<Collapse>();
    session.SetTargetSimplices(targetFaces);
    session.DoOptimization();
    session.Finalize<Collapse>();
    QHelper::TDp() = nullptr;
  }
  vcg::tri::Allocator<CMeshO>::CompactEveryVector(m);
  m.face.DisableVFAdjacency();
  m.vert.DisableVFAdjacency();
}

}  // namespace pectus::ribcage
