#include "pectus/quad/matching.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numeric>
#include <utility>

#define LEMON_ONLY_TEMPLATES
#include <lemon/matching.h>
#include <lemon/smart_graph.h>

namespace pectus::quad {

std::vector<int> greedyMatching(int nodes, const std::vector<WeightedEdge>& edges) {
  std::vector<std::size_t> order(edges.size());
  std::iota(order.begin(), order.end(), 0);
  // stable: equal weights keep the input order, so the result is deterministic
  std::stable_sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return edges[i].w > edges[j].w; });
  std::vector<int> mate(std::size_t(nodes), -1);
  for (std::size_t i : order) {
    const auto& e = edges[i];
    if (e.a == e.b || mate[e.a] >= 0 || mate[e.b] >= 0) continue;
    mate[e.a] = e.b;
    mate[e.b] = e.a;
  }
  return mate;
}

std::vector<int> maxWeightMatching(int nodes, const std::vector<WeightedEdge>& edges, bool maxCardinality) {
  using Graph = lemon::SmartGraph;
  Graph g;
  g.reserveNode(nodes);
  g.reserveEdge(int(edges.size()));
  std::vector<Graph::Node> node(static_cast<std::size_t>(nodes));
  for (int i = 0; i < nodes; ++i) node[i] = g.addNode();
  constexpr double scale = 1e6;
  std::int64_t wmax = 0;
  std::vector<std::int64_t> wi(edges.size());
  for (std::size_t i = 0; i < edges.size(); ++i) {
    wi[i] = std::llround(std::max(0.0, edges[i].w) * scale);
    wmax = std::max(wmax, wi[i]);
  }
  // a matching with one pair more always wins: offset > (max pairs) * (max weight)
  const std::int64_t offset = maxCardinality ? (std::int64_t(nodes) / 2 + 1) * (wmax + 1) : 0;
  Graph::EdgeMap<std::int64_t> weight(g);
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const auto& e = edges[i];
    if (e.a == e.b) continue;
    const std::int64_t w = wi[i] + offset;
    if (w <= 0) continue;  // a zero-weight pair never helps a maximum-weight matching
    weight[g.addEdge(node[e.a], node[e.b])] = w;
  }
  lemon::MaxWeightedMatching<Graph, Graph::EdgeMap<std::int64_t>> mwm(g, weight);
  mwm.run();
  std::vector<int> mate(std::size_t(nodes), -1);
  for (int i = 0; i < nodes; ++i) {
    const Graph::Node m = mwm.mate(node[i]);
    if (m != lemon::INVALID) mate[i] = g.id(m);
  }
  return mate;
}

double matchingWeight(const std::vector<int>& mate, const std::vector<WeightedEdge>& edges, int* pairs) {
  std::map<std::pair<int, int>, double> best;
  for (const auto& e : edges) {
    auto k = std::minmax(e.a, e.b);
    auto it = best.find(k);
    if (it == best.end() || it->second < e.w) best[k] = e.w;
  }
  double w = 0;
  int n = 0;
  for (int i = 0; i < int(mate.size()); ++i)
    if (mate[i] > i) {
      w += best.at({i, mate[i]});
      ++n;
    }
  if (pairs) *pairs = n;
  return w;
}

}  // namespace pectus::quad
