// A sweep point's result as bytes and back, to hand it from the rank that ran it to the others
// (report/sweep.hpp; MPI carries the bytes, run/ranks.hpp). Values are copied as this machine lays them
// out: every rank runs the same binary. A struct takes part by naming its members once:
//
//   struct Found { double spectrum, measured; static auto fields(auto& s) { return std::tie(s.spectrum, s.measured); } };
//
// and a type that cannot be packed (a pointer, a std::function) fails to compile where a sweep returns it.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstring>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

namespace stepwise::pack {

template <class T>
concept HasFields = requires(T& t) { T::fields(t); };

template <class T>
concept Plain = std::is_arithmetic_v<T> || std::is_enum_v<T>;

class Writer {
 public:
  const std::string& bytes() const { return bytes_; }
  void raw(const void* p, size_t n) { bytes_.append(static_cast<const char*>(p), n); }

 private:
  std::string bytes_;
};

class Reader {
 public:
  explicit Reader(std::string_view bytes) : bytes_(bytes) {}
  void raw(void* p, size_t n) {
    if (n > bytes_.size() - at_) throw std::runtime_error("a sweep's results from another rank end early: the ranks run different binaries?");
    std::memcpy(p, bytes_.data() + at_, n);
    at_ += n;
  }
  bool done() const { return at_ == bytes_.size(); }

 private:
  std::string_view bytes_;
  size_t at_ = 0;
};

template <class T>
void put(Writer& w, const T& value);
template <class T>
void get(Reader& r, T& value);

template <Plain T>
void put_one(Writer& w, const T& v) { w.raw(&v, sizeof v); }
template <Plain T>
void get_one(Reader& r, T& v) { r.raw(&v, sizeof v); }
template <class T>
  requires Plain<T>
void put_one(Writer& w, const std::complex<T>& v) { w.raw(&v, sizeof v); }
template <class T>
  requires Plain<T>
void get_one(Reader& r, std::complex<T>& v) { r.raw(&v, sizeof v); }

inline void put_one(Writer& w, const std::string& s) {
  put(w, s.size());
  w.raw(s.data(), s.size());
}
inline void get_one(Reader& r, std::string& s) {
  size_t n = 0;
  get(r, n);
  s.resize(n);
  r.raw(s.data(), n);
}

inline void put_one(Writer& w, const nlohmann::json& j) { put_one(w, j.dump()); }
inline void get_one(Reader& r, nlohmann::json& j) {
  std::string s;
  get_one(r, s);
  j = nlohmann::json::parse(s);
}

template <class T>
void put_one(Writer& w, const std::vector<T>& v) {
  put(w, v.size());
  for (const T& x : v) put(w, x);
}
template <class T>
void get_one(Reader& r, std::vector<T>& v) {
  size_t n = 0;
  get(r, n);
  v.resize(n);
  for (T& x : v) get(r, x);
}

template <class T>
void put_one(Writer& w, const std::optional<T>& v) {
  put(w, v.has_value());
  if (v) put(w, *v);
}
template <class T>
void get_one(Reader& r, std::optional<T>& v) {
  bool has = false;
  get(r, has);
  if (!has) {
    v.reset();
    return;
  }
  v.emplace();
  get(r, *v);
}

template <class A, class B>
void put_one(Writer& w, const std::pair<A, B>& p) {
  put(w, p.first);
  put(w, p.second);
}
template <class A, class B>
void get_one(Reader& r, std::pair<A, B>& p) {
  get(r, p.first);
  get(r, p.second);
}

template <class K, class V, class C>
void put_one(Writer& w, const std::map<K, V, C>& m) {
  put(w, m.size());
  for (const auto& [k, v] : m) {
    put(w, k);
    put(w, v);
  }
}
template <class K, class V, class C>
void get_one(Reader& r, std::map<K, V, C>& m) {
  size_t n = 0;
  get(r, n);
  m.clear();
  for (size_t i = 0; i < n; ++i) {
    K k;
    V v;
    get(r, k);
    get(r, v);
    m.emplace(std::move(k), std::move(v));
  }
}

// Eigen's dense vectors and matrices of numbers: the shape, then the coefficients
template <class S, int R, int C, int O, int MR, int MC>
void put_one(Writer& w, const Eigen::Matrix<S, R, C, O, MR, MC>& m) {
  put(w, static_cast<long>(m.rows()));
  put(w, static_cast<long>(m.cols()));
  w.raw(m.data(), sizeof(S) * static_cast<size_t>(m.size()));
}
template <class S, int R, int C, int O, int MR, int MC>
void get_one(Reader& r, Eigen::Matrix<S, R, C, O, MR, MC>& m) {
  long rows = 0, cols = 0;
  get(r, rows);
  get(r, cols);
  m.resize(rows, cols);
  r.raw(m.data(), sizeof(S) * static_cast<size_t>(m.size()));
}

template <HasFields T>
void put_one(Writer& w, const T& s) {
  std::apply([&](const auto&... f) { (put(w, f), ...); }, T::fields(s));
}
template <HasFields T>
void get_one(Reader& r, T& s) {
  std::apply([&](auto&... f) { (get(r, f), ...); }, T::fields(s));
}

template <class T>
void put(Writer& w, const T& value) { put_one(w, value); }
template <class T>
void get(Reader& r, T& value) { get_one(r, value); }

}  // namespace stepwise::pack
