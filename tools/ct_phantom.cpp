// pectus_ct_phantom: a patient CT export made from the parametric rib cage, for tests and benchmarks.
//   pectus_ct_phantom OUTDIR [--age 7] [--haller 4.0] [--funnel-z 1.1] [--cartilage rib|ct] [--spacing 1.0 | --spacing 0.8,0.8,1.5]
//                     [--axes RAS|LPS|native] [--metres] [--ascii] [--only nifti,masks,stl,messy] [--seed N]
// Writes into OUTDIR:
//   multilabel.nii.gz        one label map with TotalSegmentator's label table
//   masks/<name>.nii.gz      one binary mask per structure (TotalSegmentator's default output)
//   stl_clean/<name>.stl     each structure's marching-cubes surface, binary STL, scanner frame, mm
//   stl_messy/               what a real export looks like (ct_phantom_core.h, messyExport): bone.stl (ribs,
//                            vertebrae and scapulae fused, cut by the field of view, marrow shells, specks,
//                            blocks beside the spine, duplicated faces), sternum.stl (ASCII; manubrium and body
//                            apart, marrow shells, slivers, faces crossing the surface), costal_cartilages.stl
//                            (every piece, three with a hole); in metres with --metres, ASCII with --ascii
//   truth.json               parameters, the project-frame -> scanner transform, landmarks (scanner frame)
// Every output is in the scanner frame given by --axes (default RAS), millimetres unless noted.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "pectus/phantom/ct_phantom_core.h"
#include "pectus/patient/label_volume.h"
#include "pectus/errors.h"
#include "pectus/format.h"

using namespace pectus;
using namespace pectus::phantom;
namespace fs = std::filesystem;
using Vec3 = Eigen::Vector3d;

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// triangles as explicit corner positions (STL has no shared vertices)
using Tri = std::array<Vec3, 3>;
std::vector<Tri> triangles(const CMeshO& m) {
  std::vector<Tri> t;
  for (const auto& f : m.face)
    if (!f.IsD()) t.push_back({toEigen(f.cP(0)), toEigen(f.cP(1)), toEigen(f.cP(2))});
  return t;
}

std::uintmax_t writeStl(const std::string& path, const std::vector<Tri>& tris, bool ascii, double scale, const std::string& solid) {
  if (ascii) {
    std::ofstream o(path);
    o.precision(9);
    o << "solid " << solid << "\n";
    for (const auto& t : tris) {
      Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
      if (n.norm() > 0) n.normalize();
      o << "  facet normal " << n.x() << " " << n.y() << " " << n.z() << "\n    outer loop\n";
      for (const auto& p : t) o << "      vertex " << scale * p.x() << " " << scale * p.y() << " " << scale * p.z() << "\n";
      o << "    endloop\n  endfacet\n";
    }
    o << "endsolid " << solid << "\n";
    if (!o) throw IOError("cannot write '" + path + "'");
  } else {
    std::ofstream o(path, std::ios::binary);
    char header[80] = {};
    std::snprintf(header, sizeof(header), "pectus_ct_phantom %s", solid.c_str());
    o.write(header, 80);
    const std::uint32_t n = std::uint32_t(tris.size());
    o.write(reinterpret_cast<const char*>(&n), 4);
    for (const auto& t : tris) {
      Vec3 nn = (t[1] - t[0]).cross(t[2] - t[0]);
      if (nn.norm() > 0) nn.normalize();
      float buf[12];
      for (int a = 0; a < 3; ++a) buf[a] = float(nn[a]);
      for (int c = 0; c < 3; ++c)
        for (int a = 0; a < 3; ++a) buf[3 + 3 * c + a] = float(scale * t[std::size_t(c)][a]);
      o.write(reinterpret_cast<const char*>(buf), 48);
      const std::uint16_t attr = 0;
      o.write(reinterpret_cast<const char*>(&attr), 2);
    }
    if (!o) throw IOError("cannot write '" + path + "'");
  }
  return fs::file_size(path);
}

patient::LabelVolume maskOf(const patient::LabelVolume& v, const std::function<bool(std::size_t, std::int32_t)>& in) {
  patient::LabelVolume m;
  m.dims = v.dims;
  m.voxelToMm = v.voxelToMm;
  m.labels.assign(v.labels.size(), 0);
  for (std::size_t i = 0; i < v.labels.size(); ++i)
    if (in(i, v.labels[i])) m.labels[i] = 1;
  return m;
}

std::string fmt(double x) { return pectus::significantText(x, 10); }

struct Args {
  PhantomParams p;
  std::string outDir;
  bool metres = false, ascii = false;
  std::set<std::string> only{"nifti", "masks", "stl", "messy"};
};

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr,
               "%s\nusage: pectus_ct_phantom OUTDIR [--age 7] [--haller 4.0] [--funnel-z 1.1] [--cartilage rib|ct]\n"
               "       [--spacing 1.0 | --spacing 0.8,0.8,1.5]\n"
               "       [--axes RAS|LPS|native] [--metres] [--ascii] [--only nifti,masks,stl,messy] [--seed N]\n"
               "       [--edge 2.0] (centre-curve sampling of the cage model, as the generator's edge length)\n"
               "--funnel-z: the funnel centre along the sternum (the generator's funnelCenterZ; default 1.1).\n"
               "--cartilage: the costal cartilages' section, the rib's (default) or circular with twice its area (ct).\n"
               "--metres and --ascii apply to stl_messy; the sternum of stl_messy is always ASCII.\n",
               why.c_str());
  std::exit(2);
}

Args parse(int argc, char** argv) {
  Args a;
  a.p.cage.edgeLength = 2.0;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto val = [&]() -> std::string {
      if (i + 1 >= argc) usage("missing value after " + s);
      return argv[++i];
    };
    auto num = [&](const std::string& t) {
      char* end = nullptr;
      const double x = std::strtod(t.c_str(), &end);
      if (end == t.c_str() || *end) usage("not a number: '" + t + "' after " + s);
      return x;
    };
    if (s == "--age") a.p.cage.age = num(val());
    else if (s == "--haller") a.p.cage.hallerIndex = num(val());
    else if (s == "--funnel-z") a.p.cage.funnelCenterZ = num(val());  // the generator's funnelCenterZ
    else if (s == "--cartilage") {
      const std::string t = val();
      if (t != "rib" && t != "ct") usage("--cartilage takes rib or ct");
      a.p.cage.cartilageSection = t == "ct" ? pectus::ribcage::CartilageSection::Ct : pectus::ribcage::CartilageSection::Rib;
    } else if (s == "--edge") a.p.cage.edgeLength = num(val());
    else if (s == "--seed") a.p.seed = std::uint32_t(num(val()));
    else if (s == "--metres" || s == "--meters") a.metres = true;
    else if (s == "--ascii") a.ascii = true;
    else if (s == "--spacing") {
      std::string t = val();
      std::vector<double> xs;
      std::stringstream ss(t);
      std::string part;
      while (std::getline(ss, part, ',')) xs.push_back(num(part));
      if (xs.size() == 1) a.p.spacing = Vec3::Constant(xs[0]);
      else if (xs.size() == 3) a.p.spacing = Vec3(xs[0], xs[1], xs[2]);
      else usage("--spacing takes one value or three (sx,sy,sz)");
    } else if (s == "--axes") {
      const std::string t = val();
      if (t == "RAS" || t == "ras") a.p.axes = Axes::RAS;
      else if (t == "LPS" || t == "lps") a.p.axes = Axes::LPS;
      else if (t == "native") a.p.axes = Axes::Native;
      else usage("--axes must be RAS, LPS or native");
    } else if (s == "--only") {
      a.only.clear();
      std::stringstream ss(val());
      std::string part;
      while (std::getline(ss, part, ',')) {
        if (part != "nifti" && part != "masks" && part != "stl" && part != "messy") usage("--only takes nifti, masks, stl, messy");
        a.only.insert(part);
      }
    } else if (s == "-h" || s == "--help") usage("pectus_ct_phantom: a CT segmentation export made from the parametric rib cage");
    else if (!s.empty() && s[0] == '-') usage("unknown option " + s);
    else if (a.outDir.empty()) a.outDir = s;
    else usage("more than one output folder");
  }
  if (a.outDir.empty()) usage("no output folder");
  return a;
}

// The messy export (messyExport: the defects of real exports), in metres with --metres, ASCII with --ascii
void writeMessy(const Phantom& ph, const Args& a, const fs::path& dir) {
  for (const auto& f : messyExport(ph, a.p.seed)) {
    const fs::path p = dir / (f.name + ".stl");
    const std::uintmax_t bytes = writeStl(p.string(), f.tris, f.ascii || a.ascii, a.metres ? 0.001 : 1.0, f.name);
    std::printf("  %-48s %8zu triangles %10ju bytes\n", p.string().c_str(), f.tris.size(), bytes);
  }
}

void writeTruth(const Phantom& ph, const Args& a, const fs::path& path) {
  std::ofstream o(path);
  auto mat = [&](const Eigen::Matrix4d& m) {
    std::string s = "[";
    for (int r = 0; r < 4; ++r) {
      s += r ? ", [" : "[";
      for (int c = 0; c < 4; ++c) s += (c ? ", " : "") + fmt(m(r, c));
      s += "]";
    }
    return s + "]";
  };
  const auto& c = a.p.cage;
  const auto& st = ph.stats;
  o << "{\n  \"generator\": {\"age\": " << fmt(c.age) << ", \"hallerIndex\": " << fmt(c.hallerIndex) << ", \"ribPairs\": " << c.ribPairs
    << ", \"funnelCenterX\": " << fmt(c.funnelCenterX) << ", \"funnelCenterZ\": " << fmt(c.funnelCenterZ)
    << ", \"funnelWidth\": " << fmt(c.funnelWidth) << ", \"funnelHeight\": " << fmt(c.funnelHeight) << ", \"edgeLength\": " << fmt(c.edgeLength)
    << ", \"cartilageSection\": \"" << (c.cartilageSection == pectus::ribcage::CartilageSection::Ct ? "ct" : "rib") << "\""
    << ", \"seed\": " << a.p.seed << "},\n";
  o << "  \"model\": {\"hallerModel\": " << fmt(st.hallerModel) << ", \"hallerRest\": " << fmt(st.hallerRest) << ", \"funnelDepth\": "
    << fmt(st.funnelDepth) << ", \"transverseInner\": " << fmt(st.transverseInner) << ", \"apMin\": " << fmt(st.apMin)
    << ", \"chestWidth\": " << fmt(st.dims.chestWidth) << ", \"chestDepth\": " << fmt(st.dims.chestDepth) << ", \"spineHeight\": "
    << fmt(st.dims.spineHeight) << "},\n";
  o << "  \"axes\": \"" << axesName(a.p.axes) << "\",\n";
  o << "  \"spacing\": [" << fmt(a.p.spacing[0]) << ", " << fmt(a.p.spacing[1]) << ", " << fmt(a.p.spacing[2]) << "],\n";
  o << "  \"dims\": [" << ph.volume.dims[0] << ", " << ph.volume.dims[1] << ", " << ph.volume.dims[2] << "],\n";
  o << "  \"cageToScanner\": " << mat(ph.cageToScanner) << ",\n";
  o << "  \"voxelToScanner\": " << mat(ph.volume.voxelToMm) << ",\n";
  o << "  \"stlMessyUnit\": \"" << (a.metres ? "m" : "mm") << "\",\n";
  o << "  \"labels\": {";
  bool first = true;
  for (const auto& [l, n] : ph.volume.names) {
    o << (first ? "" : ", ") << "\"" << l << "\": \"" << n << "\"";
    first = false;
  }
  o << "},\n  \"strayVoxels\": {\"label\": " << ph.strayLabel << ", \"ijk\": [";
  for (std::size_t i = 0; i < ph.strays.size(); ++i)
    o << (i ? ", " : "") << "[" << ph.strays[i][0] << ", " << ph.strays[i][1] << ", " << ph.strays[i][2] << "]";
  o << "]},\n  \"landmarks\": [";
  for (std::size_t i = 0; i < ph.landmarks.size(); ++i) {
    const auto& l = ph.landmarks[i];
    o << (i ? ",\n    " : "\n    ") << "{\"code\": " << l.code << ", \"xyz\": [" << fmt(l.p.x()) << ", " << fmt(l.p.y()) << ", " << fmt(l.p.z()) << "]}";
  }
  o << "\n  ]\n}\n";
}

}  // namespace

int main(int argc, char** argv) {
  const Args a = parse(argc, argv);
  const auto tAll = Clock::now();
  try {
    const fs::path dir(a.outDir);
    fs::create_directories(dir);
    const Phantom ph = makePhantom(a.p, [](const char* w) { std::printf("%s ...\n", w); std::fflush(stdout); });
    const auto& v = ph.volume;
    std::printf("grid %d x %d x %d (%.1f M voxels), spacing %g,%g,%g mm, %zu labels, %zu stray voxels; model %.2f s, raster %.2f s\n",
                v.dims[0], v.dims[1], v.dims[2], double(v.labels.size()) * 1e-6, a.p.spacing[0], a.p.spacing[1], a.p.spacing[2],
                v.names.size(), ph.strays.size(), ph.secondsModel, ph.secondsRaster);
    auto t0 = Clock::now();
    if (a.only.count("nifti")) {
      const fs::path p = dir / "multilabel.nii.gz";
      patient::writeNifti(v, p.string());
      std::printf("  %-48s %10ju bytes\n", p.string().c_str(), fs::file_size(p));
    }
    if (a.only.count("masks")) {
      fs::remove_all(dir / "masks");
      fs::create_directories(dir / "masks");
      const std::vector<std::pair<int, std::string>> items(v.names.begin(), v.names.end());
      std::vector<std::string> errors(items.size());
      // one file per task (compression dominates); each file is the same whatever the thread
#pragma omp parallel for schedule(dynamic, 1)
      for (int n = 0; n < int(items.size()); ++n) {
        try {
          const int lab = items[std::size_t(n)].first;
          const patient::LabelVolume m = maskOf(v, [lab](std::size_t, std::int32_t x) { return x == lab; });
          patient::writeNifti(m, (dir / "masks" / (items[std::size_t(n)].second + ".nii.gz")).string());
        } catch (const std::exception& e) {
          errors[std::size_t(n)] = e.what();
        }
      }
      std::uintmax_t total = 0;
      for (std::size_t n = 0; n < items.size(); ++n) {
        if (!errors[n].empty()) throw InputError(errors[n]);
        total += fs::file_size(dir / "masks" / (items[n].second + ".nii.gz"));
      }
      std::printf("  %-48s %zu files %10ju bytes\n", (dir / "masks/").string().c_str(), v.names.size(), total);
    }
    const double tNifti = secondsSince(t0);
    t0 = Clock::now();
    if (a.only.count("stl")) {
      fs::remove_all(dir / "stl_clean");
      fs::create_directories(dir / "stl_clean");
      std::uintmax_t total = 0;
      std::size_t tris = 0;
      for (const auto& [l, name] : v.names) {
        OwnedMesh s;
        patient::extractLabelSurface(v, l, s);
        const auto t = triangles(s);
        tris += t.size();
        total += writeStl((dir / "stl_clean" / (name + ".stl")).string(), t, false, 1.0, name);
      }
      std::printf("  %-48s %zu files %zu triangles %10ju bytes\n", (dir / "stl_clean/").string().c_str(), v.names.size(), tris, total);
    }
    const double tStl = secondsSince(t0);
    t0 = Clock::now();
    if (a.only.count("messy")) {
      fs::remove_all(dir / "stl_messy");  // an earlier run's files would be imported with these
      fs::create_directories(dir / "stl_messy");
      writeMessy(ph, a, dir / "stl_messy");
    }
    const double tMessy = secondsSince(t0);
    writeTruth(ph, a, dir / "truth.json");
    std::printf("  %s\n", (dir / "truth.json").string().c_str());
    std::printf("time: model %.2f s, raster %.2f s, nifti+masks %.2f s, stl_clean %.2f s, stl_messy %.2f s, total %.2f s\n", ph.secondsModel,
                ph.secondsRaster, tNifti, tStl, tMessy, secondsSince(tAll));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pectus_ct_phantom: %s\n", e.what());
    return 1;
  }
  return 0;
}
