// Matchings on the dual graph of a triangle mesh (node = triangle, edge = a pair that makes a valid quad).
#pragma once
#include <vector>

namespace pectus::quad {

struct WeightedEdge {
  int a = -1, b = -1;
  double w = 0;  ///< weight in [0, 1] (the quad's beta)
};

/// Greedy: edges by decreasing weight, taken when both ends are free. mate[i] = matched node or -1.
std::vector<int> greedyMatching(int nodes, const std::vector<WeightedEdge>& edges);

/// Maximum-weight matching of a general graph (Edmonds' blossom algorithm, LEMON's MaxWeightedMatching
/// on integer weights, exact). With maxCardinality, among the matchings of maximum cardinality (a perfect
/// one when it exists) the one of maximum total weight: every weight is offset by a constant larger than
/// any total weight difference. Weights are rounded to 1e-6.
std::vector<int> maxWeightMatching(int nodes, const std::vector<WeightedEdge>& edges, bool maxCardinality);

/// Total weight and size of a matching given by mate[]
double matchingWeight(const std::vector<int>& mate, const std::vector<WeightedEdge>& edges, int* pairs = nullptr);

}  // namespace pectus::quad
