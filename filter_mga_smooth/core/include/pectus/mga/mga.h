// Micro-genetic algorithm (thesis chapter 2.2; Krishnakumar 1989, Carroll 1996): a population of five
// binary strings, elitism (the best string always survives), selection (roulette wheel as the thesis,
// or tournament), crossover with probability one, no mutation; when the population has nominally
// converged (almost every bit equal to the best string's), it restarts: the best is kept and the
// others are drawn anew. Maximises the fitness. Seeded and reproducible.
#pragma once
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

namespace pectus::mga {

enum class Selection { Roulette, Tournament };

struct Options {
  int population = 5;
  double accuracy = 1e-3;       ///< wanted accuracy of each design parameter (eq. 1-1)
  int maxGenerations = 60;      ///< over all restarts
  int maxRestarts = 8;
  double convergedBitFraction = 0.05;  ///< nominal convergence: fewer differing bits than this fraction
  Selection selection = Selection::Roulette;
  int tournamentSize = 2;
  std::uint64_t seed = 1;
  bool recordHistory = true;    ///< fill Result::bestHistory
};

struct Range { double lo = 0, hi = 1; };

struct Result {
  std::vector<double> x;        ///< best design parameters
  double fitness = 0;
  int generations = 0;
  int restarts = 0;
  int evaluations = 0;           ///< fitness calls (distinct strings)
  int cacheHits = 0;             ///< strings met again, whose fitness was looked up instead
  std::vector<double> bestHistory;  ///< best fitness after each generation (never decreases; Options::recordHistory)
};

/// Substring length for a parameter interval `a` and accuracy `acc`: the smallest nl with
/// a/acc <= 2^nl - 1, i.e. 2^(nl-1) < a/acc <= 2^nl of eq. 1-1 (at least 1 bit).
/// Throws pectus::InternalError unless both are positive (callers check their parameters first).
int substringLength(double interval, double accuracy);

/// Runs the micro-GA. `fitness` gets the decoded parameters; higher is better.
/// `seeds` (each of size ranges.size(), at most the population) are encoded into the first individuals,
/// so the search starts from known solutions (e.g. the node's current position) and can never end worse
/// than the best of them.
/// Throws pectus::InternalError for a population below 3, no range, an empty range, or more seeds than
/// the population or a seed of the wrong size (callers check first).
Result optimize(const std::vector<Range>& ranges, const std::function<double(const std::vector<double>&)>& fitness,
                const Options& opt, const std::vector<std::vector<double>>& seeds = {});

/// A per-item seed from a global seed and an item index (splitmix64): results do not depend on the
/// order or the thread items are processed in.
std::uint64_t itemSeed(std::uint64_t seed, std::uint64_t item);

}  // namespace pectus::mga
