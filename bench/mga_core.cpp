// The smoothing core alone on an OFF file (no meshlabserver, no file IO in the timing): for tuning and
// profiling MGA and the gradient baseline (e.g. on libcgal-demo's femur and bunny, as bench/mga_smooth.py uses them).
//
//   bench_mga_core in.off [key=value ...] [out=path.off]
//     method=mga|cg  sweeps=10  tol=1e-4  acc=1e-3  gens=20  restarts=4  pop=5  feature=60  singular=90 (either: features by angles, else crease chains)  features=creases|angles
//     guard=0.35  pass=0  active=1  all=1 (0: guided element search)  local=0 (1: guided local, implies all=0)  seed=1  cgits=10  quads=0 (faces with 4 nodes stay quads)
//
// Prints one line: "mean_before min_before mean_after min_after sweeps searches evaluations wall_s cpu_s"
// plus the fixed-node counts, and (progress=1) the mean after every sweep.
#include <omp.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>

#include "pectus/smooth/mga_smooth.h"
#include "off_reader.h"
#include "pectus/c1/surface.h"
#include "pectus/surface_cmesh.h"

namespace sm = pectus::smooth;

namespace {

double cpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s in.off [method=mga|cg sweeps= tol= acc= gens= restarts= pop= feature= singular= "
                         "guard= pass= active= seed= cgits= quads= progress= out=]\n", argv[0]);
    return 2;
  }
  std::map<std::string, std::string> kv;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    const auto eq = a.find('=');
    if (eq == std::string::npos) throw std::runtime_error("expected key=value, got " + a);
    kv[a.substr(0, eq)] = a.substr(eq + 1);
  }
  auto num = [&](const char* k, double d) { return kv.count(k) ? std::stod(kv[k]) : d; };
  sm::Options o;
  o.method = kv.count("method") && kv["method"] == "cg" ? sm::Method::ConjugateGradient : sm::Method::MicroGA;
  o.maxSweeps = int(num("sweeps", o.maxSweeps));
  o.tolerance = num("tol", o.tolerance);
  o.accuracy = num("acc", o.accuracy);
  o.generations = int(num("gens", o.generations));
  o.restarts = int(num("restarts", o.restarts));
  o.population = int(num("pop", o.population));
  if (kv.count("feature") || kv.count("singular") || (kv.count("features") && kv["features"] == "angles"))
    o.features = sm::FeatureDetection::Angles;
  o.featureAngleDeg = num("feature", o.featureAngleDeg);
  o.singularAngleDeg = num("singular", o.singularAngleDeg);
  o.worstGuard = num("guard", o.worstGuard);
  o.minPassBelow = num("pass", o.minPassBelow);
  o.activeSet = num("active", 1) != 0;
  o.elementSearch = num("local", 0) != 0 ? sm::ElementSearch::GuidedLocal
                  : num("all", 1) != 0    ? sm::ElementSearch::Every
                                          : sm::ElementSearch::Guided;
  o.seed = std::uint64_t(num("seed", 1));
  o.cgIterations = int(num("cgits", o.cgIterations));
  const bool quads = num("quads", 0) != 0;
  if (num("progress", 0) != 0)
    o.progress = [](int sweep, double mean) {
      std::printf("sweep %d mean %.5f\n", sweep, mean);
      return true;
    };

  const pectus::bench::Off off = pectus::bench::readOff(argv[1]);
  pectus::c1::TriMesh t;
  t.V = off.V;
  std::vector<int> fauxOf;  // per triangle: local edge index of the faux edge, -1 none
  for (const auto& f : off.F) {
    if (f.size() == 3) {
      t.F.push_back({f[0], f[1], f[2]});
      fauxOf.push_back(-1);
    } else if (f.size() == 4) {
      t.F.push_back({f[0], f[1], f[2]});
      t.F.push_back({f[0], f[2], f[3]});
      fauxOf.push_back(quads ? 2 : -1);  // (a b c): edge c-a
      fauxOf.push_back(quads ? 0 : -1);  // (a c d): edge a-c
    } else {
      throw std::runtime_error("faces must be triangles or quads");
    }
  }
  CMeshO m;
  pectus::toMesh(t, m);
  for (std::size_t f = 0; f < m.face.size(); ++f)
    if (fauxOf[f] >= 0) m.face[f].SetF(fauxOf[f]);
  if (quads) o.kind = pectus::ElementKind::Quads;

  const double c0 = cpuSeconds();
  const auto w0 = std::chrono::steady_clock::now();
  const sm::Result r = sm::smoothMesh(m, o);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  const double cpu = cpuSeconds() - c0;
  std::printf("fixed: %zu boundary, %zu feature, %zu singular; free %zu; threads %d\n", r.boundaryNodes, r.featureNodes,
              r.singularNodes, r.freeNodes, omp_get_max_threads());
  if (o.features == sm::FeatureDetection::Creases) std::printf("features: %s\n", r.featureSummary.c_str());
  std::printf("mean %.5f -> %.5f  min %.4f -> %.4f  folded %zu -> %zu  folds %zu -> %zu (new %zu, undone %zu+%zu)  put back (crossings) %zu  sweeps %d+%d  searches %zu  evaluations %zu  "
              "wall %.2f s (setup %.2f)  cpu %.2f s\n",
              r.before.mean, r.after.mean, r.before.min, r.after.min, r.foldedBefore, r.foldedAfter, r.foldsBefore,
              r.foldsAfter, r.foldsNew, r.movesUndoneForFolds, r.nodesPutBackFolds, r.nodesPutBack, r.sweeps,
              r.minPassSweeps, r.searches, r.evaluations, wall, r.setupSeconds, cpu);
  if (kv.count("out")) {
    std::ofstream out(kv["out"]);
    out.precision(10);
    out << "OFF\n" << r.positions.size() << ' ' << off.F.size() << " 0\n";
    for (const auto& p : r.positions) out << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    for (const auto& f : off.F) {
      out << f.size();
      for (int v : f) out << ' ' << v;
      out << '\n';
    }
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_mga_core: %s\n", e.what());
  return 1;
}
