// Peer driver for bench/mga_smooth.py: CGAL 5.5's Polygon_mesh_processing smoothers with fixed
// connectivity, and the measurements of the table (element quality with the project's own alpha/beta,
// distance to the input surface with CGAL's AABB tree), so every row is measured by the same code.
//
//   bench_mga_smooth tangential  in.off out.off iterations   # tangential_relaxation, each iteration
//                                                            # followed by projection onto the input (AABB)
//   bench_mga_smooth angle_area  in.off out.off iterations   # angle_and_area_smoothing, no Delaunay flips,
//                                                            # projected onto the input (do_project)
//   bench_mga_smooth quality     elements.off positions.off  # alpha (triangles) / beta (quads) of the
//                                                            # elements of the first file at the positions
//                                                            # of the second: "quality N min mean"
//   bench_mga_smooth distance    ref.off test.off            # "distance max mean" over test's vertices to
//                                                            # ref's surface, divided by ref's bbox diagonal
//   bench_mga_smooth folds       elements.off positions.off  # "folds IN OUT NEW": folds (pectus/folds.h) of
//                                                            # the first file's elements at its positions,
//                                                            # at the second's, and those of the second only
// Border vertices are constrained in both smoothers (as in our filters). Prints "seconds T" for the
// smoothing alone (no file IO).
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/angle_and_area_smoothing.h>
#include <CGAL/Polygon_mesh_processing/tangential_relaxation.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "off_reader.h"
#include "pectus/folds.h"
#include "pectus/quality.h"

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<Mesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
namespace PMP = CGAL::Polygon_mesh_processing;
using pectus::bench::Off;
using pectus::bench::readOff;

namespace {

Mesh readMesh(const std::string& path) {
  Mesh m;
  std::ifstream in(path);
  if (!CGAL::IO::read_OFF(in, m) || m.is_empty()) throw std::runtime_error(path + ": cannot read as a surface mesh");
  return m;
}

void writeMesh(const std::string& path, const Mesh& m) {
  std::ofstream out(path);
  out.precision(10);
  if (!CGAL::IO::write_OFF(out, m)) throw std::runtime_error(path + ": cannot write");
}

template <class F>
double timed(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 4) {
    std::cerr << "usage: " << argv[0] << " tangential|angle_area in.off out.off iterations | quality elements.off "
                                         "positions.off | distance ref.off test.off | folds elements.off positions.off\n";
    return 2;
  }
  const std::string mode = argv[1];
  if (mode == "tangential" || mode == "angle_area") {
    if (argc < 5) throw std::runtime_error("iterations missing");
    Mesh m = readMesh(argv[2]);
    const Mesh ref = m;
    const int iters = std::stoi(argv[4]);
    auto fixed = m.add_property_map<Mesh::Vertex_index, bool>("v:fixed", false).first;
    for (auto v : m.vertices()) fixed[v] = m.is_border(v);
    double s = 0;
    if (mode == "tangential") {
      s = timed([&] {
        Tree tree(faces(ref).first, faces(ref).second, ref);
        tree.accelerate_distance_queries();
        for (int i = 0; i < iters; ++i) {
          PMP::tangential_relaxation(vertices(m), m, CGAL::parameters::number_of_iterations(1).vertex_is_constrained_map(fixed));
          for (auto v : m.vertices())
            if (!fixed[v]) m.point(v) = tree.closest_point(m.point(v));
        }
      });
    } else {
      s = timed([&] {
        PMP::angle_and_area_smoothing(faces(m), m,
                                      CGAL::parameters::number_of_iterations(iters)
                                          .use_Delaunay_flips(false)
                                          .do_project(true)
                                          .vertex_is_constrained_map(fixed));
      });
    }
    writeMesh(argv[3], m);
    std::printf("seconds %.6f\n", s);
  } else if (mode == "quality") {
    const Off e = readOff(argv[2]), p = readOff(argv[3]);
    if (e.V.size() != p.V.size()) throw std::runtime_error("vertex counts differ");
    std::vector<double> q;
    for (const auto& f : e.F) {
      const auto& X = p.V;
      if (f.size() == 3) q.push_back(pectus::triangleAlpha(X[std::size_t(f[0])], X[std::size_t(f[1])], X[std::size_t(f[2])]));
      else if (f.size() == 4)
        q.push_back(pectus::quadBeta(X[std::size_t(f[0])], X[std::size_t(f[1])], X[std::size_t(f[2])], X[std::size_t(f[3])]));
      else throw std::runtime_error("faces must be triangles or quads");
    }
    const auto st = pectus::summarizeQuality(q, 10);
    std::printf("quality %zu %.6f %.6f\n", st.count, st.min, st.mean);
  } else if (mode == "distance") {
    const Mesh ref = readMesh(argv[2]);
    const Off t = readOff(argv[3]);
    Tree tree(faces(ref).first, faces(ref).second, ref);
    tree.accelerate_distance_queries();
    CGAL::Bbox_3 bb;
    for (auto v : ref.vertices()) bb += ref.point(v).bbox();
    const double diag = std::sqrt(std::pow(bb.xmax() - bb.xmin(), 2) + std::pow(bb.ymax() - bb.ymin(), 2) +
                                  std::pow(bb.zmax() - bb.zmin(), 2));
    double mx = 0, sum = 0;
    for (const auto& p : t.V) {
      const double d = std::sqrt(tree.squared_distance(Point(p.x(), p.y(), p.z())));
      mx = std::max(mx, d);
      sum += d;
    }
    std::printf("distance %.8g %.8g\n", mx / diag, sum / double(t.V.size()) / diag);
  } else if (mode == "folds") {
    const Off e = readOff(argv[2]), p = readOff(argv[3]);
    if (e.V.size() != p.V.size()) throw std::runtime_error("vertex counts differ");
    std::vector<pectus::Element> elements;
    for (const auto& f : e.F) {
      if (f.size() != 3 && f.size() != 4) throw std::runtime_error("faces must be triangles or quads");
      pectus::Element el;
      el.nv = int(f.size());
      for (std::size_t k = 0; k < f.size(); ++k) el.v[k] = f[k];
      elements.push_back(el);
    }
    const pectus::Folds folds(elements, e.V.size());
    const std::vector<char> in = folds.all(e.V), out = folds.all(p.V);
    std::size_t nIn = 0, nOut = 0, nNew = 0;
    for (std::size_t i = 0; i < in.size(); ++i) {
      nIn += in[i];
      nOut += out[i];
      nNew += out[i] && !in[i];
    }
    std::printf("folds %zu %zu %zu\n", nIn, nOut, nNew);
  } else {
    throw std::runtime_error("unknown mode " + mode);
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_mga_smooth: %s\n", e.what());
  return 1;
}
