#include "pectus/fe/tet_mesh.h"

#include <algorithm>
#include <map>
#include <unordered_map>

namespace pectus::fe {

double TetMesh::tetVolume(int t) const {
  const auto& e = tets[t];
  const Eigen::Vector3d a = nodes[e[1]] - nodes[e[0]], b = nodes[e[2]] - nodes[e[0]], c = nodes[e[3]] - nodes[e[0]];
  return a.cross(b).dot(c) / 6.0;
}

TetMesh toQuadratic(const TetMesh& lin) {
  if (lin.order == 2) return lin;
  TetMesh q;
  q.order = 2;
  q.nodes = lin.nodes;
  q.tissue = lin.tissue;
  q.tets = lin.tets;
  std::unordered_map<long long, int> mid;
  mid.reserve(lin.tets.size() * 2);
  const long long n = static_cast<long long>(lin.nodes.size());
  for (auto& e : q.tets) {
    for (int k = 0; k < 6; ++k) {
      int a = e[kTetEdges[k][0]], b = e[kTetEdges[k][1]];
      long long key = std::min(a, b) * n + std::max(a, b);
      auto it = mid.find(key);
      if (it == mid.end()) {
        it = mid.emplace(key, static_cast<int>(q.nodes.size())).first;
        q.nodes.push_back(0.5 * (lin.nodes[a] + lin.nodes[b]));
      }
      e[4 + k] = it->second;
    }
  }
  return q;
}

TetMesh structuredBox(double lx, double ly, double lz, int nx, int ny, int nz, int tissue,
                      const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& map) {
  TetMesh m;
  auto id = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  m.nodes.resize(static_cast<size_t>(nx + 1) * (ny + 1) * (nz + 1));
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        Eigen::Vector3d p(lx * i / nx, ly * j / ny, lz * k / nz);
        m.nodes[id(i, j, k)] = map ? map(p) : p;
      }
  static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          std::array<int, 10> e{};
          e[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            c[p[s]] += 1;
            e[s + 1] = id(c[0], c[1], c[2]);
          }
          m.tets.push_back(e);
          m.tissue.push_back(tissue);
          if (m.tetVolume(m.numTets() - 1) < 0) std::swap(m.tets.back()[1], m.tets.back()[2]);
        }
  return m;
}

std::vector<BoundaryFace> boundaryFaces(const TetMesh& m) {
  // faces of a positively oriented tet (0,1,2,3) with outward normals
  static const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  std::map<std::array<int, 3>, std::pair<int, int>> count;  // sorted key -> (tet*4+face, count)
  for (int t = 0; t < m.numTets(); ++t)
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> key{m.tets[t][f[k][0]], m.tets[t][f[k][1]], m.tets[t][f[k][2]]};
      std::sort(key.begin(), key.end());
      auto& c = count[key];
      c.first = t * 4 + k;
      c.second++;
    }
  auto midOf = [&](int t, int a, int b) {
    for (int k = 0; k < 6; ++k) {
      if ((kTetEdges[k][0] == a && kTetEdges[k][1] == b) || (kTetEdges[k][0] == b && kTetEdges[k][1] == a))
        return m.tets[t][4 + k];
    }
    return -1;
  };
  std::vector<BoundaryFace> out;
  for (const auto& kv : count) {
    if (kv.second.second != 1) continue;
    int t = kv.second.first / 4, k = kv.second.first % 4;
    BoundaryFace bf{};
    bf.tet = t;
    for (int i = 0; i < 3; ++i) bf.n[i] = m.tets[t][f[k][i]];
    if (m.order == 2)
      for (int i = 0; i < 3; ++i) bf.n[3 + i] = midOf(t, f[k][i], f[k][(i + 1) % 3]);
    else
      bf.n[3] = bf.n[4] = bf.n[5] = -1;
    out.push_back(bf);
  }
  return out;
}

static std::vector<Eigen::Vector3d> faceLoads(const TetMesh& m, const std::vector<BoundaryFace>& faces,
                                              const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& force) {
  std::vector<Eigen::Vector3d> F(m.nodes.size(), Eigen::Vector3d::Zero());
  for (const auto& bf : faces) {
    const Eigen::Vector3d an = 0.5 * (m.nodes[bf.n[1]] - m.nodes[bf.n[0]]).cross(m.nodes[bf.n[2]] - m.nodes[bf.n[0]]);
    const Eigen::Vector3d tot = force(an);  // total force on the face
    if (m.order == 2) {
      for (int i = 3; i < 6; ++i) F[bf.n[i]] += tot / 3.0;
    } else {
      for (int i = 0; i < 3; ++i) F[bf.n[i]] += tot / 3.0;
    }
  }
  return F;
}

std::vector<Eigen::Vector3d> pressureLoads(const TetMesh& m, const std::vector<BoundaryFace>& faces, double p) {
  return faceLoads(m, faces, [p](const Eigen::Vector3d& an) { return Eigen::Vector3d(-p * an); });
}

std::vector<Eigen::Vector3d> tractionLoads(const TetMesh& m, const std::vector<BoundaryFace>& faces,
                                           const Eigen::Vector3d& t) {
  return faceLoads(m, faces, [t](const Eigen::Vector3d& an) { return Eigen::Vector3d(t * an.norm()); });
}

}  // namespace pectus::fe
