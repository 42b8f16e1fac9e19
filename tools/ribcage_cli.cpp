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
std::string list(const std::array<Anatomy::Rib, 7>& ribs, double Anatomy::Rib::*field, double scale) {
  std::string out;
  for (const auto& r : ribs) {
    char b[32];
    std::snprintf(b, sizeof b, "%s%.0f", out.empty() ? "" : ", ", scale * (r.*field));
    out += b;
  }
  return out;
}

// the rest cage of each age beside the published figures it is compared with
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
    const Anatomy a = measureAnatomy(p);
    const double boys = 5.616 * p.age + 60.408, girls = -0.134 * p.age * p.age + 6.543 * p.age + 56.805;
    const auto ct = cartilageDiameters(a.dims, CartilageSection::Ct);
    std::printf("| %.0f | %.0f | %.0f | %.2f | %.0f (%.0f / %.0f) | %.1f x %.1f | %.1f x %.1f / %.1f | %s | %s | %s | %.1f-%.1f |\n", p.age,
                a.dims.chestWidth, a.dims.chestDepth, a.restIndex, a.sternumLength, boys, girls, a.dims.ribHeight,
                a.dims.ribThickness, a.cartilage[0], a.cartilage[1], ct[0], list(a.ribs, &Anatomy::Rib::length, 1).c_str(),
                list(a.ribs, &Anatomy::Rib::cartilage, 1).c_str(), list(a.ribs, &Anatomy::Rib::anteriorShare, 100).c_str(),
                a.sternumHalfWidth, a.fifthJunction);
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
