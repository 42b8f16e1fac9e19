#include "mga.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pectus::mga {

int substringLength(double interval, double accuracy) {
  if (!(accuracy > 0) || !(interval > 0)) throw std::invalid_argument("MGA: accuracy and interval must be positive");
  const double steps = interval / accuracy;
  int nl = 1;
  while (nl < 52 && std::ldexp(1.0, nl) - 1.0 < steps) ++nl;
  return nl;
}

std::uint64_t itemSeed(std::uint64_t seed, std::uint64_t item) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (item + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

namespace {

using Bits = std::vector<std::uint8_t>;

struct Codec {
  std::vector<Range> ranges;
  std::vector<int> len;
  int total = 0;
  std::vector<double> decode(const Bits& b) const {
    std::vector<double> x(ranges.size());
    int pos = 0;
    for (std::size_t i = 0; i < ranges.size(); ++i) {
      std::uint64_t v = 0;
      for (int k = 0; k < len[i]; ++k) v = (v << 1) | b[std::size_t(pos + k)];
      pos += len[i];
      const double maxv = std::ldexp(1.0, len[i]) - 1.0;
      x[i] = ranges[i].lo + (ranges[i].hi - ranges[i].lo) * (double(v) / maxv);
    }
    return x;
  }
  Bits encode(const std::vector<double>& x) const {
    Bits b(static_cast<std::size_t>(total));
    int pos = 0;
    for (std::size_t i = 0; i < ranges.size(); ++i) {
      const double maxv = std::ldexp(1.0, len[i]) - 1.0;
      const double t = std::clamp((x[i] - ranges[i].lo) / (ranges[i].hi - ranges[i].lo), 0.0, 1.0);
      auto v = std::uint64_t(std::llround(t * maxv));
      for (int k = len[i] - 1; k >= 0; --k) {
        b[std::size_t(pos + k)] = std::uint8_t(v & 1u);
        v >>= 1;
      }
      pos += len[i];
    }
    return b;
  }
};

}  // namespace

Result optimize(const std::vector<Range>& ranges, const std::function<double(const std::vector<double>&)>& fitness,
                const Options& opt, const std::vector<double>* seedPoint) {
  if (opt.population < 3) throw std::invalid_argument("MGA: population must be at least 3");
  if (ranges.empty()) throw std::invalid_argument("MGA: no design parameter");
  Codec codec;
  codec.ranges = ranges;
  for (const auto& r : ranges) {
    if (!(r.hi > r.lo)) throw std::invalid_argument("MGA: empty parameter range");
    codec.len.push_back(substringLength(r.hi - r.lo, opt.accuracy));
    codec.total += codec.len.back();
  }
  std::mt19937_64 rng(opt.seed);
  std::bernoulli_distribution coin(0.5);
  auto randomBits = [&]() {
    Bits b(static_cast<std::size_t>(codec.total));
    for (auto& bit : b) bit = coin(rng) ? 1 : 0;
    return b;
  };

  const std::size_t P = std::size_t(opt.population);
  std::vector<Bits> pop(P);
  std::vector<double> fit(P);
  Result res;
  auto eval = [&](const Bits& b) {
    ++res.evaluations;
    const double f = fitness(codec.decode(b));
    return std::isfinite(f) ? f : -1e300;
  };

  for (std::size_t i = 0; i < P; ++i) pop[i] = randomBits();
  if (seedPoint != nullptr && seedPoint->size() == ranges.size()) pop[0] = codec.encode(*seedPoint);
  for (std::size_t i = 0; i < P; ++i) fit[i] = eval(pop[i]);
  std::size_t bestIdx = std::size_t(std::max_element(fit.begin(), fit.end()) - fit.begin());
  Bits best = pop[bestIdx];
  double bestFit = fit[bestIdx];

  auto select = [&](void) -> std::size_t {
    if (opt.selection == Selection::Tournament) {
      std::uniform_int_distribution<std::size_t> pick(0, P - 1);
      std::size_t w = pick(rng);
      for (int t = 1; t < opt.tournamentSize; ++t) {
        const std::size_t c = pick(rng);
        if (fit[c] > fit[w]) w = c;
      }
      return w;
    }
    // roulette wheel (eq. 1-2) on fitness shifted to be positive
    const double fmin = *std::min_element(fit.begin(), fit.end());
    const double fmax = *std::max_element(fit.begin(), fit.end());
    const double shift = fmin < 0 ? -fmin : 0.0;
    const double eps = 1e-12 * (1.0 + std::abs(fmax));
    double total = 0;
    for (double f : fit) total += f + shift + eps;
    std::uniform_real_distribution<double> u(0.0, total);
    double r = u(rng), acc = 0;
    for (std::size_t i = 0; i < P; ++i) {
      acc += fit[i] + shift + eps;
      if (r <= acc) return i;
    }
    return P - 1;
  };

  std::uniform_int_distribution<int> cut(1, std::max(1, codec.total - 1));
  for (int gen = 0; gen < opt.maxGenerations; ++gen) {
    // Step 6: select parents (the elite is in the pool), crossover with probability one
    std::vector<Bits> next;
    next.reserve(P);
    next.push_back(best);
    while (next.size() < P) {
      const Bits& a = pop[select()];
      const Bits& b = pop[select()];
      const int c = cut(rng);
      Bits c1(a), c2(b);
      for (int k = c; k < codec.total; ++k) std::swap(c1[std::size_t(k)], c2[std::size_t(k)]);
      next.push_back(std::move(c1));
      if (next.size() < P) next.push_back(std::move(c2));
    }
    pop.swap(next);
    fit[0] = bestFit;
    for (std::size_t i = 1; i < P; ++i) fit[i] = eval(pop[i]);
    for (std::size_t i = 1; i < P; ++i)
      if (fit[i] > bestFit) { bestFit = fit[i]; best = pop[i]; }
    res.generations = gen + 1;
    res.bestHistory.push_back(bestFit);

    // Step 7: nominal convergence -> restart around the kept best
    std::size_t differing = 0;
    for (std::size_t i = 0; i < P; ++i)
      for (int k = 0; k < codec.total; ++k) differing += pop[i][std::size_t(k)] != best[std::size_t(k)];
    if (double(differing) < opt.convergedBitFraction * double(codec.total * int(P))) {
      if (res.restarts >= opt.maxRestarts) break;
      ++res.restarts;
      pop[0] = best;
      fit[0] = bestFit;
      for (std::size_t i = 1; i < P; ++i) {
        pop[i] = randomBits();
        fit[i] = eval(pop[i]);
        if (fit[i] > bestFit) { bestFit = fit[i]; best = pop[i]; }
      }
    }
  }
  res.x = codec.decode(best);
  res.fitness = bestFit;
  return res;
}

}  // namespace pectus::mga
