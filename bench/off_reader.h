// A minimal OFF reader for the bench drivers (triangles, quads or any polygon per face; colours ignored).
#pragma once
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "pectus/quality.h"

namespace pectus::bench {

struct Off {
  std::vector<Vec3> V;
  std::vector<std::vector<int>> F;
};

inline Off readOff(const std::string& path) {
  std::ifstream in(path);
  std::string head;
  in >> head;
  if (head != "OFF") throw std::runtime_error(path + ": not an OFF file");
  std::size_t nv = 0, nf = 0, ne = 0;
  in >> nv >> nf >> ne;
  Off o;
  o.V.resize(nv);
  for (auto& p : o.V) in >> p.x() >> p.y() >> p.z();
  o.F.resize(nf);
  for (auto& f : o.F) {
    int k = 0;
    in >> k;
    f.resize(std::size_t(k));
    for (auto& v : f) in >> v;
    std::string rest;
    std::getline(in, rest);  // colours, if any
  }
  if (!in) throw std::runtime_error(path + ": truncated OFF file");
  return o;
}

}  // namespace pectus::bench
