// The phantom as a segmentation tool's surface export, with the defects of real exports (ct_phantom_core.h).
#include <algorithm>
#include <map>
#include <random>
#include <set>


#include "pectus/phantom/ct_phantom_core.h"
#include "pectus/union_find.h"

namespace pectus::phantom {

namespace {
using Vec3 = Eigen::Vector3d;

// a binary mask on the phantom's grid
struct Mask {
  const patient::LabelVolume* v;
  std::vector<std::uint8_t> m;
  std::size_t idx(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(v->dims[0]) * (std::size_t(j) + std::size_t(v->dims[1]) * std::size_t(k));
  }
  bool at(int i, int j, int k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < v->dims[0] && j < v->dims[1] && k < v->dims[2] && m[idx(i, j, k)];
  }
};

Mask maskOf(const patient::LabelVolume& v, const std::function<bool(std::int32_t)>& in) {
  Mask m{&v, std::vector<std::uint8_t>(v.labels.size(), 0)};
  for (std::size_t i = 0; i < v.labels.size(); ++i) m.m[i] = in(v.labels[i]) ? 1 : 0;
  return m;
}

// the voxels of m whose six neighbours are in m too
Mask eroded(const Mask& m) {
  Mask e{m.v, std::vector<std::uint8_t>(m.m.size(), 0)};
  const auto& d = m.v->dims;
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i)
        e.m[e.idx(i, j, k)] = m.at(i, j, k) && m.at(i - 1, j, k) && m.at(i + 1, j, k) && m.at(i, j - 1, k) && m.at(i, j + 1, k) &&
                              m.at(i, j, k - 1) && m.at(i, j, k + 1);
  return e;
}

// the mask's marching-cubes surface, facing out (or in: a cavity's boundary)
std::vector<Triangle> surface(const Mask& m, bool inward = false) {
  patient::LabelVolume l;
  l.dims = m.v->dims;
  l.voxelToMm = m.v->voxelToMm;
  l.labels.assign(m.m.begin(), m.m.end());
  OwnedMesh s;
  patient::extractLabelSurface(l, 1, s);
  std::vector<Triangle> t;
  for (const auto& f : s.face)
    if (!f.IsD()) {
      t.push_back({toEigen(f.cP(0)), toEigen(f.cP(1)), toEigen(f.cP(2))});
      if (inward) std::swap(t.back()[1], t.back()[2]);
    }
  return t;
}

void append(std::vector<Triangle>& to, const std::vector<Triangle>& t) { to.insert(to.end(), t.begin(), t.end()); }

bool isRib(const std::string& n) { return n.rfind("rib_", 0) == 0; }
bool isVertebra(const std::string& n) { return n.rfind("vertebrae_", 0) == 0; }

// the k range of the labels `in`, the phantom's stray voxels left out
std::pair<int, int> zRange(const Phantom& ph, const std::function<bool(std::int32_t)>& in) {
  const patient::LabelVolume& v = ph.volume;
  const std::set<std::array<int, 3>> strays(ph.strays.begin(), ph.strays.end());
  int lo = v.dims[2], hi = -1;
  for (int k = 0; k < v.dims[2]; ++k)
    for (int j = 0; j < v.dims[1]; ++j)
      for (int i = 0; i < v.dims[0]; ++i)
        if (in(v.at(i, j, k)) && !strays.count({i, j, k})) lo = std::min(lo, k), hi = std::max(hi, k);
  return {lo, hi};
}

}  // namespace

std::vector<ExportedFile> messyExport(const Phantom& ph, std::uint32_t seed) {
  const patient::LabelVolume& v = ph.volume;
  std::mt19937 rng(seed * 2654435761u + 17u);
  auto uni = [&](int n) { return int((std::uint64_t(rng()) * std::uint64_t(n)) >> 32); };
  const int nx = v.dims[0], ny = v.dims[1], nz = v.dims[2];
  const auto name = [&](std::int32_t l) {
    const auto it = v.names.find(l);
    return it == v.names.end() ? std::string() : it->second;
  };
  std::vector<ExportedFile> out;

  // --- bone: ribs, vertebrae and scapulae in one mask, cut by the field of view
  {
    const auto bony = [&](std::int32_t l) {
      const std::string n = name(l);
      return isRib(n) || isVertebra(n) || n.rfind("scapula_", 0) == 0;
    };
    Mask bone = maskOf(v, bony);
    const int kTop = zRange(ph, [&](std::int32_t l) { return name(l) == "vertebrae_T1"; }).second - 2;
    const int kBottom = zRange(ph, [&](std::int32_t l) { return isRib(name(l)); }).first + 8;
    for (int k = 0; k < nz; ++k)
      if (k > kTop || k < kBottom)
        for (int j = 0; j < ny; ++j)
          for (int i = 0; i < nx; ++i) bone.m[bone.idx(i, j, k)] = 0;
    // two blocks of bone beside the column near the 6th ribs' heads, 2 voxels clear of everything
    const Eigen::Matrix4d toVoxel = v.voxelToMm.inverse();
    int blocks = 0;
    for (int side = 1; side <= 2; ++side) {
      const auto j6 = std::find_if(ph.landmarks.begin(), ph.landmarks.end(), [&](const Landmark& l) { return l.code == 100 * side + 6; });
      if (j6 == ph.landmarks.end()) continue;
      const Vec3 c = (toVoxel * j6->p.homogeneous()).head<3>();
      // 6 x 9 x 7 voxels (about 300 mm^3 as a surface), from 2 voxels lateral of the joint outward: it reaches
      // the column's cut band and lies mostly beyond it
      constexpr int bx = 6, by = 9, bz = 7;
      const bool leftward = (v.voxelToMm.topLeftCorner<3, 3>().inverse() * ph.cageToScanner.topLeftCorner<3, 3>() * Vec3(side == 2 ? 1 : -1, 0, 0)).x() > 0;
      bool placed = false;
      for (int r = 0; r < 24 && !placed; ++r)
        for (int dk = -r; dk <= r && !placed; ++dk)
          for (int dj = -r; dj <= r && !placed; ++dj) {
            const int i0 = leftward ? int(c.x()) + 2 : int(c.x()) - 2 - bx, j0 = int(c.y()) + dj, k0 = int(c.z()) + dk;
            bool clear = i0 > 2 && j0 > 2 && k0 > kBottom + 2 && i0 + bx + 2 < nx && j0 + by + 2 < ny && k0 + bz + 2 < kTop;
            for (int k = k0 - 2; clear && k < k0 + bz + 2; ++k)
              for (int j = j0 - 2; clear && j < j0 + by + 2; ++j)
                for (int i = i0 - 2; clear && i < i0 + bx + 2; ++i) clear = v.at(i, j, k) == 0;
            if (!clear) continue;
            for (int k = k0; k < k0 + bz; ++k)
              for (int j = j0; j < j0 + by; ++j)
                for (int i = i0; i < i0 + bx; ++i) bone.m[bone.idx(i, j, k)] = 1;
            placed = true;
            ++blocks;
          }
    }
    // specks: single voxels at least 3 voxels from anything and from each other
    int specks = 0;
    for (int attempt = 0; attempt < 4000000 && specks < 900; ++attempt) {
      const int i = 3 + uni(nx - 6), j = 3 + uni(ny - 6), k = std::max(kBottom, 3) + uni(std::max(1, std::min(kTop, nz - 4) - std::max(kBottom, 3)));
      bool clear = true;
      for (int dk = -3; clear && dk <= 3; ++dk)
        for (int dj = -3; clear && dj <= 3; ++dj)
          for (int di = -3; clear && di <= 3; ++di) clear = v.at(i + di, j + dj, k + dk) == 0 && !bone.at(i + di, j + dj, k + dk);
      if (!clear) continue;
      bone.m[bone.idx(i, j, k)] = 1;
      ++specks;
    }
    std::vector<Triangle> t = surface(bone);
    // a marrow shell inside each rib and vertebra (within the field of view)
    for (const auto& [l, n] : v.names) {
      if (!isRib(n) && !isVertebra(n)) continue;
      Mask own = maskOf(v, [&](std::int32_t x) { return x == l; });
      for (std::size_t q = 0; q < own.m.size(); ++q) own.m[q] = own.m[q] && bone.m[q];
      append(t, surface(eroded(own), true));
    }
    // 619 faces written twice
    std::set<std::size_t> twice;
    while (twice.size() < 619 && twice.size() < t.size()) twice.insert(std::size_t(uni(int(t.size()))));
    for (std::size_t f : twice) t.push_back(t[f]);
    out.push_back({"bone", std::move(t), false});
    (void)blocks;
  }

  // --- sternum: manubrium and body apart, each with a marrow shell; slivers; a patch through the surface
  {
    Mask st = maskOf(v, [](std::int32_t l) { return l == kSternumLabel; });
    const auto [k0, k1] = zRange(ph, [](std::int32_t l) { return l == kSternumLabel; });
    const int kSplit = k1 - (k1 - k0) / 4;  // the manubriosternal joint
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) st.m[st.idx(i, j, kSplit)] = 0;
    std::vector<Triangle> t = surface(st);
    append(t, surface(eroded(st), true));
    const std::size_t solid = t.size();
    // ten slivers: two triangles of a 0.6 mm square, 1.5 mm off the surface
    for (int s = 0; s < 10 && solid; ++s) {
      const Triangle& f = t[std::size_t(uni(int(solid)))];
      const Vec3 c = (f[0] + f[1] + f[2]) / 3.0, n = (f[1] - f[0]).cross(f[2] - f[0]).normalized();
      const Vec3 u = (f[1] - f[0]).normalized() * 0.6, w = n.cross(u).normalized() * 0.6, p = c + 1.5 * n;
      t.push_back({p, p + u, p + u + w});
      t.push_back({p, p + u + w, p + w});
    }
    // a patch of faces copied, tilted 25 degrees and moved 0.3 mm so that they cross the surface
    if (solid) {
      const Triangle seedFace = t[std::size_t(uni(int(solid)))];
      const Vec3 c0 = (seedFace[0] + seedFace[1] + seedFace[2]) / 3.0;
      const Vec3 n = (seedFace[1] - seedFace[0]).cross(seedFace[2] - seedFace[0]).normalized();
      const Eigen::Matrix3d R = Eigen::AngleAxisd(25.0 * 3.14159265358979323846 / 180, (seedFace[1] - seedFace[0]).normalized()).toRotationMatrix();
      std::vector<Triangle> patch;
      for (std::size_t f = 0; f < solid; ++f)
        if (((t[f][0] + t[f][1] + t[f][2]) / 3.0 - c0).norm() < 1.6 * v.spacing().maxCoeff()) patch.push_back(t[f]);
      for (const auto& tr : patch) {
        Triangle q;
        for (int k = 0; k < 3; ++k) q[std::size_t(k)] = c0 + R * (tr[std::size_t(k)] - c0) + 0.3 * n;
        t.push_back(q);
      }
    }
    out.push_back({"sternum", std::move(t), true});
  }

  // --- costal cartilages: one file, a hole of 3-6 faces in three of its pieces
  {
    std::vector<Triangle> t = surface(maskOf(v, [](std::int32_t l) { return l == kCartilageLabel; }));
    // the faces as pieces (sharing corners)
    std::map<std::array<double, 3>, int> corner;
    UnionFind sets;
    std::vector<std::array<int, 3>> F;
    for (const auto& f : t) {
      std::array<int, 3> ids{};
      for (int k = 0; k < 3; ++k) {
        const auto [it, fresh] = corner.emplace(std::array<double, 3>{f[std::size_t(k)].x(), f[std::size_t(k)].y(), f[std::size_t(k)].z()},
                                                int(sets.size()));
        if (fresh) sets.add();
        ids[std::size_t(k)] = it->second;
      }
      sets.unite(ids[1], ids[0]);
      sets.unite(ids[2], ids[0]);
      F.push_back(ids);
    }
    std::map<int, std::vector<std::size_t>> pieces;
    for (std::size_t f = 0; f < F.size(); ++f) pieces[sets.find(F[f][0])].push_back(f);
    std::vector<std::vector<std::size_t>> bySize;
    for (auto& [root, faces] : pieces) bySize.push_back(faces);
    std::stable_sort(bySize.begin(), bySize.end(), [](const auto& a, const auto& b) { return a.size() > b.size(); });
    std::set<std::size_t> gone;
    for (std::size_t p = 0; p < std::min<std::size_t>(3, bySize.size()); ++p) {
      // a seed face and the faces sharing its corners, 3-6 in all
      const auto& faces = bySize[p];
      const std::size_t seedFace = faces[std::size_t(uni(int(faces.size())))];
      const std::size_t want = 3 + std::size_t(uni(4));
      std::vector<std::size_t> hole{seedFace};
      for (std::size_t f : faces) {
        if (hole.size() >= want) break;
        if (f == seedFace) continue;
        for (int a = 0; a < 3 && std::find(hole.begin(), hole.end(), f) == hole.end(); ++a)
          for (int b = 0; b < 3; ++b)
            if (F[f][std::size_t(a)] == F[seedFace][std::size_t(b)]) {
              hole.push_back(f);
              break;
            }
      }
      gone.insert(hole.begin(), hole.end());
    }
    std::vector<Triangle> kept;
    for (std::size_t f = 0; f < t.size(); ++f)
      if (!gone.count(f)) kept.push_back(t[f]);
    out.push_back({"costal_cartilages", std::move(kept), false});
  }
  return out;
}

}  // namespace pectus::phantom
