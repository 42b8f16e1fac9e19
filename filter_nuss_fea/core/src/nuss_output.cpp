#include "pectus/nuss/nuss_output.h"

#include <algorithm>
#include <cmath>

#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/color.h>
#include <vcg/complex/algorithms/update/normal.h>

#include "pectus/errors.h"
#include "pectus/format.h"

namespace pectus::nuss {

std::string resultBase(std::string path) {
  if (path.size() > 4 && path.compare(path.size() - 4, 4, ".vtu") == 0) path.resize(path.size() - 4);
  return path;
}

OutputFiles filesAt(const std::string& base, int pathSide, int pathRib) {
  OutputFiles f;
  f.vtu = base + ".vtu";
  f.inp = base + ".inp";
  f.curveCsv = base + "_force_displacement.csv";
  f.ribStrainCsv = base + "_rib_strain.csv";
  f.pathSide = pathSide;
  f.pathRib = pathRib;
  return f;
}

fe::InpOptions inpOptions(const Analysis& a, const Options& opt) {
  fe::InpOptions io;
  io.nlgeom = opt.nonlinear;
  io.increments = std::max(10, static_cast<int>(std::ceil(a.force / opt.curveStep)));
  io.printNodes = a.sternumNodes;
  io.heading = "pectus-meshlab Nuss FE model, Fe = " + fixedText(a.force, 2) + " N";
  return io;
}

void writeOutputs(const OutputFiles& files, const Analysis& a, const Options& opt) {
  if (!files.vtu.empty()) fe::writeVtu(files.vtu, a.mesh, &a.result);
  if (!files.inp.empty()) fe::writeCalculixInp(files.inp, problemAt(a, opt, a.force), inpOptions(a, opt));
  if (!files.curveCsv.empty()) writeCurveCsv(files.curveCsv, a);
  if (!files.ribStrainCsv.empty()) writeRibPathCsv(files.ribStrainCsv, strainAlongRib(a, files.pathSide, files.pathRib));
}

std::FILE* openOutput(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw IOError("Cannot write '" + path + "': check the folder exists and is writable.");
  return f;
}

void closeOutput(std::FILE* f, const std::string& path) {
  if (std::fclose(f) != 0) throw IOError("Cannot finish writing '" + path + "'.");
}

void writeCurveCsv(const std::string& path, const Analysis& a) {
  std::FILE* f = openOutput(path);
  std::fprintf(f, "force_N,elevation_mm\n");
  for (const auto& p : a.curve) std::fprintf(f, "%.6g,%.6g\n", p.first, p.second);
  closeOutput(f, path);
}

void writeRibPathCsv(const std::string& path, const std::vector<PathSample>& samples) {
  std::FILE* f = openOutput(path);
  std::fprintf(f, "distance_from_sternum_midline_mm,tissue,mean_equivalent_strain,max_equivalent_strain,mean_von_mises_MPa,tets\n");
  for (const auto& s : samples)
    std::fprintf(f, "%.3f,%s,%.6g,%.6g,%.6g,%d\n", s.distance, tissueName(Tissue(s.tissue)), s.meanStrain, s.maxStrain, s.meanStress, s.tets);
  closeOutput(f, path);
}

void deformedSurface(CMeshO& out, CMeshO& analysed, const CageSurface& cage, const Analysis& a,
                     const std::vector<double>& nodal) {
  copyLabelledMesh(out, analysed);
  // the copy holds the live vertices of the analysed surface in order; its vertex k is FE node nodeOfVertex[i]
  for (size_t i = 0, k = 0; i < analysed.vert.size(); ++i) {
    if (analysed.vert[i].IsD()) continue;
    auto& v = out.vert[k++];
    const int n = cage.nodeOfVertex[i];
    if (n < 0) continue;  // referenced by no face: not in the model, left where it was
    const Eigen::Vector3d d = a.result.displacement(n);
    v.P() += Point3m(Scalarm(d.x()), Scalarm(d.y()), Scalarm(d.z()));
    v.Q() = Scalarm(nodal[std::size_t(n)]);
  }
  std::vector<float> q;
  for (const auto& v : out.vert)
    if (!v.IsD()) q.push_back(v.Q());
  std::sort(q.begin(), q.end());
  const float hi = q.empty() ? 1.0f : std::max(q[std::min(q.size() - 1, size_t(0.98 * q.size()))], 1e-12f);
  vcg::tri::UpdateColor<CMeshO>::PerVertexQualityRamp(out, hi, 0.0f);  // red = high, blue = low
  vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFaceNormalized(out);
  vcg::tri::UpdateBounding<CMeshO>::Box(out);
}

}  // namespace pectus::nuss
