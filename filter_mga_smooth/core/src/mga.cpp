#include "pectus/mga/mga.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "pectus/errors.h"

namespace pectus::mga {

int substringLength(double interval, double accuracy) {
  if (!(accuracy > 0) || !(interval > 0)) throw InternalError("MGA: accuracy and interval must be positive");
  const double steps = interval / accuracy;
  int nl = 1;
  double p = 2.0;  // 2^nl (doubling is exact)
  while (nl < 52 && p - 1.0 < steps) {
    ++nl;
    p *= 2.0;
  }
  return nl;
}

std::uint64_t itemSeed(std::uint64_t seed, std::uint64_t item) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (item + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

namespace {

/// xoshiro256** (Blackman and Vigna), seeded by splitmix64: a 32-byte state, so seeding one run per
/// node and element costs nothing (std::mt19937_64 fills 2.5 kB); a UniformRandomBitGenerator
class Xoshiro {
 public:
  using result_type = std::uint64_t;
  explicit Xoshiro(std::uint64_t seed) {
    for (auto& w : s_) w = seed = itemSeed(seed, 0);
  }
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return ~result_type(0); }
  result_type operator()() {
    const std::uint64_t r = rotl(s_[1] * 5, 7) * 9, t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return r;
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4];
};

/// A string of `total` bits packed into 64-bit words: bit k (parameter after parameter, most significant
/// first) is bit 63 - k % 64 of word k / 64; unused low bits of the last word stay zero.
struct Codec {
  std::vector<Range> ranges;
  std::vector<int> len;
  std::vector<double> maxv;  ///< 2^len - 1
  int total = 0, words = 1;
  static bool bit(const std::uint64_t* b, int k) { return (b[k >> 6] >> (63 - (k & 63))) & 1u; }
  void decode(const std::uint64_t* b, std::vector<double>& x) const {
    int pos = 0;
    for (std::size_t i = 0; i < ranges.size(); ++i) {
      std::uint64_t v = 0;
      if ((pos >> 6) == ((pos + len[i] - 1) >> 6))  // within one word: one shift
        v = (b[pos >> 6] << (pos & 63)) >> (64 - len[i]);
      else
        for (int k = 0; k < len[i]; ++k) v = (v << 1) | std::uint64_t(bit(b, pos + k));
      pos += len[i];
      x[i] = ranges[i].lo + (ranges[i].hi - ranges[i].lo) * (double(v) / maxv[i]);
    }
  }
  void encode(const std::vector<double>& x, std::uint64_t* b) const {
    std::fill(b, b + words, 0);
    int pos = 0;
    for (std::size_t i = 0; i < ranges.size(); ++i) {
      const double t = std::clamp((x[i] - ranges[i].lo) / (ranges[i].hi - ranges[i].lo), 0.0, 1.0);
      const auto v = std::uint64_t(std::llround(t * maxv[i]));
      for (int k = 0; k < len[i]; ++k)
        if ((v >> (len[i] - 1 - k)) & 1u) b[(pos + k) >> 6] |= std::uint64_t(1) << (63 - ((pos + k) & 63));
      pos += len[i];
    }
  }
  /// mask of the bits k >= c in word w
  std::uint64_t tailMask(int w, int c) const {
    if (c <= 64 * w) return ~std::uint64_t(0);
    if (c >= 64 * (w + 1)) return 0;
    return (std::uint64_t(1) << (64 - (c & 63))) - 1;
  }
  /// mask of the used bits of word w
  std::uint64_t usedMask(int w) const { return ~tailMask(w, total); }
};

/// fitness of the strings met so far in one run (single-word strings, the word is the key): open
/// addressing, grows at half load. The table is reused from run to run (see Workspace): a slot belongs to the
/// current run when its stamp is the run's, so starting a run clears nothing and allocates nothing.
class Memo {
 public:
  void reset() {
    count_ = 0;
    if (++stamp_ == 0) {  // the stamp wrapped: clear once
      std::fill(stamps_.begin(), stamps_.end(), 0u);
      stamp_ = 1;
    }
  }
  bool find(std::uint64_t key, double& f) const {
    if (keys_.empty()) return false;
    for (std::size_t i = slot(key);; i = (i + 1) & (keys_.size() - 1)) {
      if (stamps_[i] != stamp_) return false;
      if (keys_[i] == key) {
        f = vals_[i];
        return true;
      }
    }
  }
  void insert(std::uint64_t key, double f) {
    if (2 * (count_ + 1) > keys_.size()) grow();
    std::size_t i = slot(key);
    while (stamps_[i] == stamp_) i = (i + 1) & (keys_.size() - 1);
    stamps_[i] = stamp_;
    keys_[i] = key;
    vals_[i] = f;
    ++count_;
  }

 private:
  /// Fibonacci hashing: the top bits of the product (keys hold their bits at the top of the word)
  std::size_t slot(std::uint64_t key) const { return std::size_t(((key ^ (key >> 32)) * 0x9E3779B97F4A7C15ull) >> shift_); }
  void grow() {
    std::vector<std::uint64_t> k;
    std::vector<double> v;
    std::vector<std::uint32_t> u;
    k.swap(keys_);
    v.swap(vals_);
    u.swap(stamps_);
    const std::size_t n = k.empty() ? 128 : 2 * k.size();
    shift_ = 64 - __builtin_ctzll(n);
    keys_.assign(n, 0);
    vals_.assign(n, 0);
    stamps_.assign(n, 0u);
    count_ = 0;
    for (std::size_t i = 0; i < k.size(); ++i)
      if (u[i] == stamp_) insert(k[i], v[i]);
  }
  std::vector<std::uint64_t> keys_;
  std::vector<double> vals_;
  std::vector<std::uint32_t> stamps_;
  std::size_t count_ = 0;
  std::uint32_t stamp_ = 1;
  int shift_ = 57;
};

/// bits set in x (SWAR: inline on any x86-64, where __builtin_popcountll calls libgcc without -mpopcnt)
inline std::size_t popcount(std::uint64_t x) {
  x = x - ((x >> 1) & 0x5555555555555555ull);
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0Full;
  return std::size_t((x * 0x0101010101010101ull) >> 56);
}

/// the buffers of one run, reused from run to run on a thread: a run allocates nothing but its Result
/// (a fitness function that itself runs optimize() gets a workspace of its own)
struct Workspace {
  Codec codec;
  std::vector<std::uint64_t> pop, next, best;
  std::vector<double> fit, wheel, x;
  Memo memo;
};
thread_local Workspace tlWorkspace;
thread_local int tlDepth = 0;
struct DepthGuard {
  DepthGuard() { ++tlDepth; }
  ~DepthGuard() { --tlDepth; }
  DepthGuard(const DepthGuard&) = delete;
  DepthGuard& operator=(const DepthGuard&) = delete;
};

/// the inputs optimize() refuses: throws InternalError
void checkInputs(const std::vector<Range>& ranges, const Options& opt, const std::vector<std::vector<double>>& seeds) {
  if (opt.population < 3) throw InternalError("MGA: population must be at least 3");
  if (ranges.empty()) throw InternalError("MGA: no design parameter");
  if (seeds.size() > std::size_t(opt.population)) throw InternalError("MGA: more seeds than the population");
  for (const auto& s : seeds)
    if (s.size() != ranges.size()) throw InternalError("MGA: a seed of the wrong size");
}

/// the codec of the parameters' ranges: each range's substring length for the accuracy, packed after the
/// previous one (throws InternalError for an empty range)
void setUpCodec(Codec& codec, const std::vector<Range>& ranges, double accuracy) {
  codec.ranges.assign(ranges.begin(), ranges.end());
  codec.len.clear();
  codec.maxv.clear();
  codec.total = 0;
  for (const auto& r : ranges) {
    if (!(r.hi > r.lo)) throw InternalError("MGA: empty parameter range");
    codec.len.push_back(substringLength(r.hi - r.lo, accuracy));
    codec.maxv.push_back(double(std::uint64_t(1) << codec.len.back()) - 1.0);
    codec.total += codec.len.back();
  }
  codec.words = (codec.total + 63) / 64;
}

/// One run of the micro-GA on a workspace whose codec is set up. Strings live in the workspace's flat
/// buffers (individual i at i * W): no allocation per generation.
class Run {
 public:
  Run(Workspace& ws, const std::function<double(const std::vector<double>&)>& fitness, const Options& opt,
      std::size_t parameters)
      : codec_(ws.codec),
        fitness_(fitness),
        opt_(opt),
        W_(std::size_t(ws.codec.words)),
        P_(std::size_t(opt.population)),
        rng_(opt.seed),
        pop_(ws.pop),
        next_(ws.next),
        best_(ws.best),
        fit_(ws.fit),
        wheel_(ws.wheel),
        x_(ws.x),
        memo_(ws.memo),
        useMemo_(W_ == 1),
        cut_(1, std::max(1, ws.codec.total - 1)) {
    pop_.assign(P_ * W_, 0);
    next_.assign(P_ * W_, 0);
    best_.assign(W_, 0);
    fit_.assign(P_, 0.0);
    if (opt.recordHistory) res_.bestHistory.reserve(std::size_t(std::max(opt.maxGenerations, 0)));
    memo_.reset();
    x_.assign(parameters, 0.0);
    wheel_.assign(P_, 0.0);
  }

  /// the first population: random strings, the seeds in the first places; its best is kept
  void start(const std::vector<std::vector<double>>& seeds) {
    for (std::size_t i = 0; i < P_; ++i) randomBits(ind(pop_, i));
    for (std::size_t i = 0; i < seeds.size(); ++i) codec_.encode(seeds[i], ind(pop_, i));
    for (std::size_t i = 0; i < P_; ++i) fit_[i] = eval(ind(pop_, i));
    const std::size_t bestIdx = std::size_t(std::max_element(fit_.begin(), fit_.end()) - fit_.begin());
    std::copy_n(ind(pop_, bestIdx), W_, best_.begin());
    bestFit_ = fit_[bestIdx];
  }

  /// Step 6: select parents (the elite is in the pool), one-point crossover with probability one; the
  /// children replace the population, the elite first
  void breed() {
    std::copy(best_.begin(), best_.end(), ind(next_, 0));
    if (opt_.selection == Selection::Roulette) buildWheel();
    for (std::size_t n = 1; n < P_;) {
      const std::uint64_t* a = ind(pop_, select());
      const std::uint64_t* b = ind(pop_, select());
      const int c = cut_(rng_);
      std::uint64_t* c1 = ind(next_, n++);
      std::uint64_t* c2 = n < P_ ? ind(next_, n++) : nullptr;
      for (std::size_t w = 0; w < W_; ++w) {
        const std::uint64_t tail = codec_.tailMask(int(w), c);
        c1[w] = (a[w] & ~tail) | (b[w] & tail);
        if (c2) c2[w] = (b[w] & ~tail) | (a[w] & tail);
      }
    }
    pop_.swap(next_);
  }

  /// the children's fitness (the elite keeps its own) and the best of them, recorded as generation `gen`
  void evaluateChildren(int gen) {
    fit_[0] = bestFit_;
    for (std::size_t i = 1; i < P_; ++i) fit_[i] = eval(ind(pop_, i));
    for (std::size_t i = 1; i < P_; ++i)
      if (fit_[i] > bestFit_) {
        bestFit_ = fit_[i];
        std::copy_n(ind(pop_, i), W_, best_.begin());
      }
    res_.generations = gen + 1;
    if (opt_.recordHistory) res_.bestHistory.push_back(bestFit_);
  }

  /// Step 7: nominal convergence, the population's bits differing from the best's below the fraction
  bool converged() const {
    std::size_t differing = 0;
    for (std::size_t i = 0; i < P_; ++i)
      for (std::size_t w = 0; w < W_; ++w) differing += popcount(ind(pop_, i)[w] ^ best_[w]);
    return double(differing) < opt_.convergedBitFraction * double(codec_.total * int(P_));
  }

  /// Step 7: a restart around the kept best, if restarts are left (else false)
  bool restart() {
    if (res_.restarts >= opt_.maxRestarts) return false;
    ++res_.restarts;
    std::copy(best_.begin(), best_.end(), ind(pop_, 0));
    fit_[0] = bestFit_;
    for (std::size_t i = 1; i < P_; ++i) {
      randomBits(ind(pop_, i));
      fit_[i] = eval(ind(pop_, i));
      if (fit_[i] > bestFit_) {
        bestFit_ = fit_[i];
        std::copy_n(ind(pop_, i), W_, best_.begin());
      }
    }
    return true;
  }

  /// the result: the best string decoded, its fitness and the run's counts
  Result finish() {
    res_.x.resize(codec_.ranges.size());
    codec_.decode(best_.data(), res_.x);
    res_.fitness = bestFit_;
    return std::move(res_);
  }

 private:
  std::uint64_t* ind(std::vector<std::uint64_t>& buf, std::size_t i) const { return buf.data() + i * W_; }
  void randomBits(std::uint64_t* b) {
    for (std::size_t w = 0; w < W_; ++w) b[w] = rng_() & codec_.usedMask(int(w));
  }
  /// The fitness is a function of the string alone, and a micro-GA breeds many copies of the same string
  /// (crossover of near-identical parents, the converged population): each distinct string is evaluated
  /// once per run and looked up afterwards (strings of up to 64 bits; longer ones are not cached). The
  /// search itself - selection, crossover, restarts - is unchanged.
  double eval(const std::uint64_t* b) {
    double f = 0;
    if (useMemo_ && memo_.find(b[0], f)) {
      ++res_.cacheHits;
      return f;
    }
    ++res_.evaluations;
    codec_.decode(b, x_);
    f = fitness_(x_);
    if (!std::isfinite(f)) f = -1e300;
    if (useMemo_) memo_.insert(b[0], f);
    return f;
  }
  /// roulette wheel (eq. 1-2) on fitness shifted to be positive: the cumulative sums, once per generation
  void buildWheel() {
    const double fmin = *std::min_element(fit_.begin(), fit_.end());
    const double fmax = *std::max_element(fit_.begin(), fit_.end());
    const double shift = fmin < 0 ? -fmin : 0.0;
    const double eps = 1e-12 * (1.0 + std::abs(fmax));
    double acc = 0;
    for (std::size_t i = 0; i < P_; ++i) wheel_[i] = acc += fit_[i] + shift + eps;
  }
  /// a parent: by tournament, or on the roulette wheel
  std::size_t select() {
    if (opt_.selection == Selection::Tournament) {
      std::uniform_int_distribution<std::size_t> pick(0, P_ - 1);
      std::size_t w = pick(rng_);
      for (int t = 1; t < opt_.tournamentSize; ++t) {
        const std::size_t c = pick(rng_);
        if (fit_[c] > fit_[w]) w = c;
      }
      return w;
    }
    std::uniform_real_distribution<double> u(0.0, wheel_[P_ - 1]);
    const double r = u(rng_);
    for (std::size_t i = 0; i < P_; ++i)
      if (r <= wheel_[i]) return i;
    return P_ - 1;
  }

  const Codec& codec_;
  const std::function<double(const std::vector<double>&)>& fitness_;
  const Options& opt_;
  const std::size_t W_, P_;
  Xoshiro rng_;
  std::vector<std::uint64_t>& pop_;
  std::vector<std::uint64_t>& next_;
  std::vector<std::uint64_t>& best_;
  std::vector<double>& fit_;
  std::vector<double>& wheel_;
  std::vector<double>& x_;
  Memo& memo_;
  const bool useMemo_;
  std::uniform_int_distribution<int> cut_;
  Result res_;
  double bestFit_ = 0;
};

}  // namespace

Result optimize(const std::vector<Range>& ranges, const std::function<double(const std::vector<double>&)>& fitness,
                const Options& opt, const std::vector<std::vector<double>>& seeds) {
  checkInputs(ranges, opt, seeds);
  std::unique_ptr<Workspace> own;
  Workspace& ws = tlDepth == 0 ? tlWorkspace : *(own = std::make_unique<Workspace>());
  const DepthGuard depth;
  setUpCodec(ws.codec, ranges, opt.accuracy);
  Run run(ws, fitness, opt, ranges.size());
  run.start(seeds);
  for (int gen = 0; gen < opt.maxGenerations; ++gen) {
    run.breed();
    run.evaluateChildren(gen);
    if (run.converged() && !run.restart()) break;
  }
  return run.finish();
}

}  // namespace pectus::mga
