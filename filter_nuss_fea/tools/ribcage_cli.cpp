// Command-line driver of the rib cage core: timings, measured Haller index, topology checks, optional PLY;
// or the model's anatomy by age, beside the published figures it is compared with (docs/validation.md).
//   pectus_ribcage_cli [edgeLength] [hallerIndex] [age] [ribPairs] [out.ply] [--check]
//   pectus_ribcage_cli --anatomy [5,8,11,14,17]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <set>
#include <string>

#include <vcg/complex/algorithms/clean.h>
#include <vcg/complex/algorithms/update/topology.h>
#include <wrap/io_trimesh/export_ply.h>

#include "pectus/ribcage/haller.h"
#include "pectus/mesh_checks.h"
#include "pectus/ribcage/ribcage.h"
#include "pectus/ribcage/ribcage_model.h"
#include "pectus/surface_cmesh.h"

using namespace pectus;
using namespace pectus::ribcage;

namespace {
// arc length of a curve's centre line from parameter u0 to u1, over the samples with |x| >= xMin
double arcLength(const Curve& c, double u0, double u1, double xMin) {
  double len = 0;
  for (std::size_t i = 1; i < c.c.size(); ++i)
    if (c.u[i - 1] >= u0 && c.u[i] <= u1 && std::abs(c.c[i].x()) >= xMin && std::abs(c.c[i - 1].x()) >= xMin)
      len += (c.c[i] - c.c[i - 1]).norm();
  return len;
}

// the rest cage (no funnel) of each age: chest, sternum, sections, and per rib level the length of the rib
// from its costovertebral joint to the sternum's edge, its cartilage's, and the cartilage's share of the
// anterior rib (from the rib's lateral point to the sternum's edge)
int anatomy(const std::string& ages) {
  std::printf("| age | chest width mm | depth mm | index without funnel | sternum length mm (Li et al. boys / girls) |"
              " rib section mm | cartilage section mm, rib's / CT | ribs 1-7: rib length mm | cartilage length mm |"
              " cartilage share of the anterior rib %% | 5th cartilage, mm from the midline |\n"
              "|---:|---:|---:|---:|---|---|---|---|---|---|---|\n");
  std::size_t pos = 0;
  while (pos < ages.size()) {
    const std::size_t next = std::min(ages.find(',', pos), ages.size());
    RibCageParams p;
    p.age = std::atof(ages.substr(pos, next - pos).c_str());
    pos = next + 1;
    RibCageStats st;
    p.hallerIndex = kHallerIndexRange.hi;  // any valid index: the rest index is measured first
    try {
      buildCalibratedModel(p, &st);
    } catch (const std::exception&) {
    }
    const Dimensions d = validate(p);
    const CageModel m = buildModel(d, p, 0.0, 1.0);
    const double boys = 5.616 * p.age + 60.408, girls = -0.134 * p.age * p.age + 6.543 * p.age + 56.805;
    const auto rib = cartilageDiameters(d, CartilageSection::Rib), ct = cartilageDiameters(d, CartilageSection::Ct);
    std::string lens, carts, index;
    double fifth = 0;  // the 5th costochondral junction's distance from the midline
    for (const Curve& c : m.curves) {
      if (c.side != 1 || c.rib < 1 || c.rib > 7) continue;
      const double edge = 0.5 * d.sternumWidth;  // the sternum's edge, at the body's width
      std::size_t iLat = 0;  // the lateral point: where the anterior rib begins
      for (std::size_t i = 0; i < c.c.size(); ++i)
        if (std::abs(c.c[i].x()) > std::abs(c.c[iLat].x())) iLat = i;
      const double total = arcLength(c, 0, 1, edge), cart = arcLength(c, c.uCartilage, 1, edge);
      const double anterior = arcLength(c, c.u[iLat], 1, edge);
      if (c.rib == 5)  // the thesis' Fig. 6-18 measures along the 5th's lateral distance from the sternum's centre
        for (std::size_t i = 1; i < c.c.size(); ++i)
          if (c.u[i - 1] < c.uCartilage && c.u[i] >= c.uCartilage) fifth = std::abs(c.c[i].x());
      char b[64];
      std::snprintf(b, sizeof b, "%s%.0f", lens.empty() ? "" : ", ", total);
      lens += b;
      std::snprintf(b, sizeof b, "%s%.0f", carts.empty() ? "" : ", ", cart);
      carts += b;
      std::snprintf(b, sizeof b, "%s%.0f", index.empty() ? "" : ", ", 100 * cart / anterior);
      index += b;
    }
    std::printf("| %.0f | %.0f | %.0f | %.2f | %.0f (%.0f / %.0f) | %.1f x %.1f | %.1f x %.1f / %.1f | %s | %s | %s | %.1f-%.1f |\n", p.age,
                d.chestWidth, d.chestDepth, st.hallerRest, m.zNotch - m.zTip, boys, girls, d.ribHeight, d.ribThickness, rib[0], rib[1],
                ct[0], lens.c_str(), carts.c_str(), index.c_str(), 0.5 * d.sternumWidth, fifth);
  }
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  RibCageParams p;
  bool check = false;
  std::string out;
  if (argc >= 2 && !std::strcmp(argv[1], "--anatomy")) return anatomy(argc >= 3 ? argv[2] : "5,8,11,14,17");
  int pos = 0;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--check")) { check = true; continue; }
    switch (pos++) {
      case 0: p.edgeLength = std::atof(argv[i]); break;
      case 1: p.hallerIndex = std::atof(argv[i]); break;
      case 2: p.age = std::atof(argv[i]); break;
      case 3: p.ribPairs = std::atoi(argv[i]); break;
      case 4: out = argv[i]; break;
      default: break;
    }
  }
  pectus::OwnedMesh m;
  RibCageStats st;
  const auto t0 = std::chrono::steady_clock::now();
  const auto lms = generateRibCage(p, m, &st);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto h = measureHaller(m);
  std::printf("edge %.2f grid %.3f: %d faces (%zu raw, %d decimation retries), %d vertices, %.2f s (calibration %.2f, extract %.2f, decimate %.2f, label %.2f)\n",
              p.edgeLength, st.gridSpacing, m.fn, st.rawFaces, st.decimationRetries, m.vn, secs, st.secondsField, st.secondsExtract,
              st.secondsDecimate, st.secondsLabel);
  std::printf("Haller requested %.4f model %.4f mesh %.4f (T %.2f AP %.2f at z %.1f), rest %.3f, depth %.2f mm\n",
              p.hallerIndex, st.hallerModel, h ? h->index : -1.0, h ? h->transverse : -1.0, h ? h->ap : -1.0,
              h ? h->zAp : 0.0, st.hallerRest, st.funnelDepth);
  if (check) {
    m.face.EnableFFAdjacency();
    m.face.EnableMark();
    vcg::tri::UpdateTopology<CMeshO>::FaceFace(m);
    std::vector<CFaceO*> si;
    for (int f : selfIntersectingFaces(m)) si.push_back(&m.face[std::size_t(f)]);
    std::vector<std::pair<int, CFaceO*>> cc;
    const int ncc = vcg::tri::Clean<CMeshO>::ConnectedComponents(m, cc);
    std::printf("self-intersecting faces %zu, non-manifold edges %zu, components %d\n", si.size(),
                pectus::inspectMesh(m).nonManifoldEdges, ncc);  // (vcglib's CountNonManifoldEdgeFF leaks bit flags)
    for (auto* f : si) {
      const int q = int(f->Q() + 0.5f);
      std::printf("  si face part %d at %.1f %.1f %.1f\n", q, f->P(0)[0], f->P(0)[1], f->P(0)[2]);
    }
    // parts per component
    vcg::tri::UpdateFlags<CMeshO>::FaceClearV(m);
    for (auto& c : cc) {
      std::set<int> parts;
      std::vector<CFaceO*> st2{c.second};
      c.second->SetV();
      while (!st2.empty()) {
        CFaceO* f = st2.back();
        st2.pop_back();
        parts.insert(int(f->Q() + 0.5f) % 1000);
        for (int k = 0; k < 3; ++k) {
          CFaceO* g = f->FFp(k);
          if (!g->IsV()) { g->SetV(); st2.push_back(g); }
        }
      }
      std::printf("  component of %d faces:", c.first);
      for (int q : parts) std::printf(" %d", q);
      std::printf("\n");
    }
  }
  if (!out.empty()) {
    vcg::tri::io::ExporterPLY<CMeshO>::Save(m, out.c_str(), vcg::tri::io::Mask::IOM_FACECOLOR | vcg::tri::io::Mask::IOM_FACEQUALITY, false);
  }
  (void)lms;
  return 0;
}
