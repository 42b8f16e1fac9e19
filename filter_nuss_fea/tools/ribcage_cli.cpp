// Command-line driver of the rib cage core: timings, measured Haller index, topology checks, optional PLY.
//   pectus_ribcage_cli [edgeLength] [hallerIndex] [age] [ribPairs] [out.ply] [--check]
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
#include "pectus/surface_cmesh.h"

using namespace pectus;
using namespace pectus::ribcage;

int main(int argc, char** argv) {
  RibCageParams p;
  bool check = false;
  std::string out;
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
