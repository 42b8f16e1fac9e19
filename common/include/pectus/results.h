#pragma once
// The figures a filter returns: an ordered list of named values, each a number (double), a count (integer),
// a text or a place (three coordinates). The adapter base hands them to the host: as the filter's return
// values on MeshLab 2021.05 and later (what pymeshlab's apply_filter returns), as a JSON line in the file
// named by $PECTUS_RESULTS_FILE and a Log line on 2020.09 (docs/DEVELOPING.md, "Results").
//
// Keys are snake_case with the unit as suffix: force_N, elevation_mm, max_stress_MPa, max_stress_at_mm (a
// place), max_stress_where (a text), slice_volume_change_cm3, seconds. No Qt: a core or a command-line driver
// can fill one too.
#include <array>
#include <cstddef>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace pectus {

class Results {
 public:
  using Vec3 = std::array<double, 3>;
  /// a number, a count, a text or a place
  using Value = std::variant<double, long long, std::string, Vec3>;
  struct Entry {
    std::string key;
    Value value;
  };

  /// Sets `key` to `v`: an existing key keeps its place and takes the new value, a new one is appended.
  void set(const std::string& key, Value v);
  template <class T, std::enable_if_t<std::is_floating_point_v<T>, int> = 0>
  void set(const std::string& key, T v) {
    set(key, Value(double(v)));
  }
  template <class T, std::enable_if_t<std::is_integral_v<T> && !std::is_same_v<T, bool>, int> = 0>
  void set(const std::string& key, T v) {
    set(key, Value(static_cast<long long>(v)));
  }
  void set(const std::string& key, const char* v) { set(key, Value(std::string(v))); }
  void set(const std::string& key, const std::string& v) { set(key, Value(v)); }
  void set(const std::string& key, const Vec3& v) { set(key, Value(v)); }
  /// a flag is given as a count (0 or 1) or a text, by choice of the caller
  void set(const std::string& key, bool v) = delete;

  /// the value of `key`, or nullptr
  const Value* find(const std::string& key) const;
  bool has(const std::string& key) const { return find(key) != nullptr; }
  /// a number or a count as double; throws std::out_of_range if `key` is missing or not numeric
  double number(const std::string& key) const;

  const std::vector<Entry>& entries() const { return entries_; }
  std::size_t size() const { return entries_.size(); }
  bool empty() const { return entries_.empty(); }
  void clear() { entries_.clear(); }

  /// One JSON object {"key": value, ...} in the order set: numbers with 17 significant digits (they read back
  /// to the same double) and always with a '.' or an exponent, so that a reader tells them from counts; a
  /// number that is not finite as null; a place as [x, y, z]; texts escaped (quotes, backslashes, control
  /// characters; UTF-8 passes unchanged).
  std::string toJson() const;
  /// One line for people: "key = value, key = value" (numbers with 6 significant digits, texts in quotes,
  /// places as (x, y, z)).
  std::string toText() const;

  /// `s` as a JSON string, quotes included
  static std::string jsonString(const std::string& s);
  /// `v` as a JSON number (17 significant digits, with '.' or exponent), or null when not finite
  static std::string jsonNumber(double v);

 private:
  std::vector<Entry> entries_;
};

}  // namespace pectus
