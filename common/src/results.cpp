#include "pectus/results.h"

#include "pectus/format.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace pectus {

void Results::set(const std::string& key, Value v) {
  for (auto& e : entries_)
    if (e.key == key) {
      e.value = std::move(v);
      return;
    }
  entries_.push_back({key, std::move(v)});
}

const Results::Value* Results::find(const std::string& key) const {
  for (const auto& e : entries_)
    if (e.key == key) return &e.value;
  return nullptr;
}

double Results::number(const std::string& key) const {
  const Value* v = find(key);
  if (v == nullptr) throw std::out_of_range("no result '" + key + "'");
  if (const auto* d = std::get_if<double>(v)) return *d;
  if (const auto* i = std::get_if<long long>(v)) return double(*i);
  throw std::out_of_range("result '" + key + "' is not a number");
}

std::string Results::jsonString(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      case '\b': out += "\\b"; break;
      case '\f': out += "\\f"; break;
      default:
        if (u < 0x20 || u == 0x7f) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", unsigned(u));
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::string Results::jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  std::string s = significantText(v, 17);
  if (s.find_first_of(".eE") == std::string::npos) s += ".0";  // a number, not a count, to the reader
  return s;
}

namespace {
std::string json(const Results::Value& v) {
  if (const auto* d = std::get_if<double>(&v)) return Results::jsonNumber(*d);
  if (const auto* i = std::get_if<long long>(&v)) return std::to_string(*i);
  if (const auto* s = std::get_if<std::string>(&v)) return Results::jsonString(*s);
  const auto& p = std::get<Results::Vec3>(v);
  return "[" + Results::jsonNumber(p[0]) + ", " + Results::jsonNumber(p[1]) + ", " + Results::jsonNumber(p[2]) + "]";
}

std::string short6(double v) {
  if (!std::isfinite(v)) return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
  return significantText(v, 6);
}

std::string text(const Results::Value& v) {
  if (const auto* d = std::get_if<double>(&v)) return short6(*d);
  if (const auto* i = std::get_if<long long>(&v)) return std::to_string(*i);
  if (const auto* s = std::get_if<std::string>(&v)) return "\"" + *s + "\"";
  const auto& p = std::get<Results::Vec3>(v);
  return "(" + short6(p[0]) + ", " + short6(p[1]) + ", " + short6(p[2]) + ")";
}
}  // namespace

std::string Results::toJson() const {
  std::string out = "{";
  for (std::size_t i = 0; i < entries_.size(); ++i)
    out += (i ? ", " : "") + jsonString(entries_[i].key) + ": " + json(entries_[i].value);
  return out + "}";
}

std::string Results::toText() const {
  std::string out;
  for (std::size_t i = 0; i < entries_.size(); ++i)
    out += (i ? ", " : "") + entries_[i].key + " = " + text(entries_[i].value);
  return out;
}

}  // namespace pectus
