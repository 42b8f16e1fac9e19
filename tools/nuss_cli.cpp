// Command-line driver of the Nuss FE analysis core (bench/nuss_convergence.py, quick studies):
//   pectus_nuss_cli [--edge mm] [--haller h] [--age y] [--order 1|2] [--maxvol mm3] [--quality q]
//                   [--target mm|chest | --force N] [--chest-line] [--linear] [--space s] [--sc-radius mm] [--threads n]
//                   [--vtu out.vtu] [--layers]
//                   [--inp deck.inp] [--blend mm] [--funnel-z f] [--material svk|neo-hookean|neo-hookean-ccx]
//                   [--calibration force|displacement] [--line-search] [--adaptive-steps] [--plain-newton]
//                   [--bone-e MPa] [--cartilage-e MPa] [--cartilage rib|ct] [--rib-stress] [--help]
// Builds the default rib cage (--layers: as one layer per tissue, joined as the filter's 'One layer per
// tissue' input does), runs the analysis and prints one line of key=value figures, the mean displacement
// of the sternal load patch's nodes and the tets' volume per tissue. --vtu and --inp write the model and its
// result, and the same model at the final force as a CalculiX deck, through the FE filter's writer
// (pectus/nuss/nuss_output.h: the same files as its BASE.vtu and BASE.inp, with the same increments and heading),
// printing the sternal patch's nodes, which is what bench/fe_vs_ccx.py --cases cage compares. --material: every tissue's large-displacement model;
// --calibration: how --target is reached (a force search, or one displacement-controlled solve);
// --line-search, --adaptive-steps: the Newton options of those names (fe/solver.h), on by default as in the
// analysis; --plain-newton turns both off. --bone-e, --cartilage-e: the tissues' Young's moduli (default
// the thesis': 11500 and 12.25 MPa). --target chest
// calibrates to the chest line depth (the FE filter's target 0); --chest-line prints the chest line and
// the target the analysis would take, and stops before TetGen. --cartilage: the costal cartilages' section
// (the generator's cartilageSection: the rib's, or circular with twice its area). --rib-stress prints, for
// each rib, its bone's von Mises stress in the posterior, middle and anterior third of its length (by
// straight distance from its costovertebral joint, tets touching a fixed or loaded node left out), and
// where its largest stress lies: how far from the joint, from the nearest tet of its costal cartilage and
// from the nearest node carrying a rib support force. --sc-radius holds the anterior translation of the
// sternum's surface nodes within that radius of the jugular notch (Placement::sternoclavicularRadius: the
// clavicles' hold on the manubrium; 0, the default, leaves it to the ribs as the thesis and the FE filter do).
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "pectus/nuss/nuss_analysis.h"
#include "pectus/nuss/nuss_output.h"
#include "pectus/errors.h"
#include "pectus/ribcage/ribcage.h"
#include "pectus/nuss/tissue_join.h"

using namespace pectus;

namespace {
// --rib-stress: each rib's bone stress by thirds of its length, and where its peak lies
void printRibStress(const nuss::Analysis& a, const std::vector<Landmark>& lms) {
  const std::vector<char> special = nuss::supportAndLoadNodes(a);  // as the analysis' maxima
  auto percentile = [](std::vector<double> v, double q) {
    if (v.empty()) return 0.0;
    const auto k = static_cast<std::size_t>(q * double(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
    return v[k];
  };
  std::printf("rib stress (von Mises MPa of the bone's tets; p99 / max per third of the rib's length from its joint)\n");
  for (int side = 1; side <= 2; ++side)
    for (int rib = 1; rib <= 12; ++rib) {
      const int part = ribPart(side, rib);
      const auto joint = findLandmark(lms, part);
      if (!joint) continue;
      std::vector<int> bone, cart;
      double reach = 0;
      for (int t = 0; t < a.mesh.numTets(); ++t) {
        if (a.tetPart[t] != part) continue;
        if (a.mesh.tissue[t] == int(Tissue::Cartilage)) cart.push_back(t);
        if (a.mesh.tissue[t] != int(Tissue::Bone)) continue;
        bone.push_back(t);
        reach = std::max(reach, (a.mesh.centroid(t) - *joint).norm());
      }
      if (bone.empty()) continue;
      std::array<std::vector<double>, 3> third;
      int peak = -1;
      for (int t : bone) {
        if (nuss::touches(a.mesh, t, special)) continue;
        const double d = (a.mesh.centroid(t) - *joint).norm();
        third[std::min(2, static_cast<int>(3 * d / reach))].push_back(a.result.vonMises[t]);
        if (peak < 0 || a.result.vonMises[t] > a.result.vonMises[peak]) peak = t;
      }
      if (peak < 0) continue;
      double toCart = -1;
      for (int t : cart) {
        const double d = (a.mesh.centroid(t) - a.mesh.centroid(peak)).norm();
        if (toCart < 0 || d < toCart) toCart = d;
      }
      std::printf("%s rib %d: length %.0f mm;", side == 1 ? "right" : "left", rib, reach);
      const char* names[3] = {"posterior", "middle", "anterior"};
      for (int k = 0; k < 3; ++k)
        std::printf(" %s %.1f / %.1f;", names[k], percentile(third[k], 0.99),
                    third[k].empty() ? 0.0 : *std::max_element(third[k].begin(), third[k].end()));
      double toSupport = -1;  // the nearest node carrying an Fsr
      for (const auto& v : a.supportNodes)
        for (int n : v) {
          const double d = (a.mesh.nodes[n] - a.mesh.centroid(peak)).norm();
          if (toSupport < 0 || d < toSupport) toSupport = d;
        }
      std::printf(" peak %.1f at %.0f mm from the joint, %.1f mm from its cartilage, %.1f mm from a bar support\n",
                  a.result.vonMises[peak], (a.mesh.centroid(peak) - *joint).norm(), toCart, toSupport);
    }
}
}  // namespace

int main(int argc, char** argv) {
  ribcage::RibCageParams rp;
  rp.edgeLength = 4.0;
  nuss::Options o;
  o.targetElevation = 0;
  std::string vtu, inp;
  bool ribStress = false;
  bool layers = false, chestOnly = false;
  for (int i = 1; i < argc; ++i) {
    auto next = [&]() -> const char* {
      if (i + 1 >= argc) { std::fprintf(stderr, "missing value after %s\n", argv[i]); std::exit(2); }
      return argv[++i];
    };
    const std::string a = argv[i];
    if (a == "--edge") rp.edgeLength = std::atof(next());
    else if (a == "--haller") rp.hallerIndex = std::atof(next());
    else if (a == "--age") rp.age = std::atof(next());
    else if (a == "--order") o.mesh.order = std::atoi(next());
    else if (a == "--maxvol") o.mesh.maxVolume = std::atof(next());
    else if (a == "--quality") o.mesh.radiusEdgeRatio = std::atof(next());
    else if (a == "--target") {
      const std::string v = next();
      if (v == "chest") o.targetFromChestLine = true;
      else o.targetElevation = std::atof(v.c_str());
    }
    else if (a == "--chest-line") chestOnly = true;
    else if (a == "--force") o.force = std::atof(next());
    else if (a == "--linear") o.nonlinear = false;
    else if (a == "--space") o.place.intercostalSpace = std::atoi(next());
    else if (a == "--sc-radius") o.place.sternoclavicularRadius = std::atof(next());
    else if (a == "--joint-radius") o.place.jointRadius = std::atof(next());
    else if (a == "--vtu") vtu = next();
    else if (a == "--layers") layers = true;
    else if (a == "--inp") inp = next();
    else if (a == "--blend") rp.blend = std::atof(next());
    else if (a == "--funnel-z") rp.funnelCenterZ = std::atof(next());
    else if (a == "--material" || a == "--calibration") {
      const std::string v = next();
      try {
        if (a == "--material") o.material = fe::parseMaterialModel(v);
        else o.calibration = nuss::parseCalibrationMethod(v);
      } catch (const InputError& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
      }
    }
    else if (a == "--line-search") o.newton.lineSearch = true;
    else if (a == "--adaptive-steps") o.newton.adaptiveSteps = true;
    else if (a == "--plain-newton") o.newton.lineSearch = o.newton.adaptiveSteps = false;
    else if (a == "--bone-e") o.eBone = std::atof(next());
    else if (a == "--cartilage-e") o.eCartilage = std::atof(next());
    else if (a == "--cartilage") {
      const std::string v = next();
      if (v != "rib" && v != "ct") { std::fprintf(stderr, "--cartilage takes rib or ct\n"); return 2; }
      rp.cartilageSection = v == "ct" ? ribcage::CartilageSection::Ct : ribcage::CartilageSection::Rib;
    }
    else if (a == "--rib-stress") ribStress = true;
    else if (a == "--help" || a == "-h") {
      std::printf(
          "pectus_nuss_cli [--edge mm] [--haller h] [--age y] [--order 1|2] [--maxvol mm3] [--quality q]\n"
          "                [--target mm|chest | --force N] [--chest-line] [--linear] [--space s] [--sc-radius mm] [--joint-radius mm] [--vtu out.vtu] [--layers] [--inp deck.inp]\n"
          "                [--blend mm] [--funnel-z f] [--material svk|neo-hookean|neo-hookean-ccx] [--calibration force|displacement]\n"
          "                [--line-search] [--adaptive-steps] [--plain-newton] [--bone-e MPa] [--cartilage-e MPa]\n"
          "                [--cartilage rib|ct] [--rib-stress]\n"
          "Builds the generator's rib cage, runs the Nuss FE analysis and prints key=value figures.\n"
          "Defaults: the analysis' (the FE filter's): neo-Hookean, displacement control, Newton with a line search\n"
          "and adaptive load steps; --plain-newton turns both off.\n");
      return 0;
    }
    else { std::fprintf(stderr, "usage: see the header of tools/nuss_cli.cpp (unknown argument %s)\n", argv[i]); return 2; }
  }
  try {
    pectus::OwnedMesh cage;
    const auto t0 = std::chrono::steady_clock::now();
    std::array<pectus::OwnedMesh, 3> tissues;
    const auto lms = layers ? ribcage::generateTissueLayers(rp, tissues) : ribcage::generateRibCage(rp, cage);
    nuss::CageSurface surf;
    if (layers) {
      std::vector<nuss::TissueLayer> tl;
      for (std::size_t k = 0; k < 3; ++k) tl.push_back({ribcage::kTissueLayerNames[k], &tissues[k]});
      nuss::JoinStats js;
      surf = nuss::joinTissueLayers(tl, lms, cage, &js);
      std::printf("joined %d layers: %.1f mm3 in the layers, %.1f mm3 in the union, %d components\n", js.layers,
                  js.sumVolume, js.unionVolume, js.components);
    } else {
      surf = nuss::cageFromMesh(cage);
    }
    const double tCage = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (chestOnly) {
      const auto t = nuss::resolveTarget(surf, lms, o);
      std::printf("chestDepth=%.3f reach=%.3f target=%.3f\ntarget %s\n", t.chest ? t.chest->depth : 0.0,
                  t.chest ? t.chest->reach() : 0.0, t.elevation, t.describe().c_str());
      return 0;
    }
    const auto a = nuss::analyze(surf, lms, o);
    std::printf("faces=%zu tets=%d nodes=%d order=%d dofs=%d force=%.2f elevation=%.3f compliance=%.5f "
                "maxStress=%.3f maxStrain=%.4f strainCart=%.4f strainBone=%.5f maxStressAll=%.3f nlSolves=%d newton=%d factor=%d "
                "tCage=%.2f tMesh=%.2f tSolve=%.2f material=%s calibration=%s eBone=%.1f eCartilage=%.3f\n",
                surf.surface.F.size(), a.mesh.numTets(), a.mesh.numNodes(), a.mesh.order,
                3 * a.mesh.numNodes() - 3 * int(a.fixedNodes.size()), a.force, a.elevation, a.linearCompliance,
                a.maxStress, a.maxStrain, a.maxStrainCartilage, a.maxStrainBone, a.maxStressAll, a.nonlinearSolves,
                a.newtonIterations, a.factorizations, tCage, a.secondsMesh, a.secondsSolve, fe::materialModelName(o.material),
                nuss::calibrationMethodName(o.calibration), o.eBone, o.eCartilage);
    std::printf("target %s\n", a.target.describe().c_str());
    std::printf("max stress at %s\nmax stress away from the tissue junctions %.3f at %s\nmax strain at %s\n",
                a.maxStressAt.describe().c_str(), a.maxStressBody, a.maxStressBodyAt.describe().c_str(),
                a.maxStrainAt.describe().c_str());
    std::printf("fixed %zu, sternoclavicular %zu, sternum %zu, supports", a.fixedNodes.size(), a.sternoclavicularNodes.size(),
                a.sternumNodes.size());
    for (size_t k = 0; k < a.supportNodes.size(); ++k) std::printf(" %s:%zu", a.supportNames[k].c_str(), a.supportNodes[k].size());
    if (a.calibration) {
      std::printf("\ncalibration");
      for (const auto& [f, d] : a.calibration->history) std::printf(" %.3f:%.3f", f, d);
    }
    std::printf("\ncurve");
    for (const auto& p : a.curve) std::printf(" %.2f:%.3f", p.first, p.second);
    std::printf("\n");
    double vol[4] = {0, 0, 0, 0};
    for (int t = 0; t < a.mesh.numTets(); ++t) vol[std::clamp(a.mesh.tissue[std::size_t(t)], 0, 3)] += std::abs(a.mesh.tetVolume(t));
    std::printf("tet volume mm3: bone %.1f cartilage %.1f sternum %.1f other %.1f\n", vol[int(Tissue::Bone)],
                vol[int(Tissue::Cartilage)], vol[int(Tissue::Sternum)], vol[0]);
    Eigen::Vector3d um = Eigen::Vector3d::Zero();
    for (int n : a.sternumNodes) um += a.result.u.segment<3>(3 * n);
    if (!a.sternumNodes.empty()) um /= double(a.sternumNodes.size());
    std::printf("sternal patch mean displacement mm: %.6e %.6e %.6e (%zu nodes)\n", um.x(), um.y(), um.z(),
                a.sternumNodes.size());
    if (ribStress) printRibStress(a, lms);
    nuss::OutputFiles files;  // the FE filter's writer: the same .vtu and .inp as its BASE files
    files.vtu = vtu;
    files.inp = inp;
    nuss::writeOutputs(files, a, o);
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
