#include "run/provenance.hpp"

#include "run/ranks.hpp"
#include "solvers/periodic_fft.hpp"

// the libraries' version macros (their headers' only use here)
#include <Eigen/Core>
#include <suitesparse/SuiteSparse_config.h>
#include <boost/version.hpp>
#include <gsl/gsl_version.h>
#include <sundials/sundials_config.h>

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <numeric>
#include <thread>

#ifndef STEPWISE_COMMIT
#define STEPWISE_COMMIT "unknown"
#endif

namespace stepwise {

namespace {

std::string utc(std::chrono::system_clock::time_point t) {
  return fmt::format("{:%Y-%m-%dT%H:%M:%S}Z", std::chrono::floor<std::chrono::seconds>(t));
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.starts_with("model name"))
      if (const auto colon = line.find(':'); colon != std::string::npos) return line.substr(line.find_first_not_of(" \t", colon + 1));
  return "unknown";
}

std::string host() {
  char name[256] = {};
  return gethostname(name, sizeof name - 1) == 0 ? std::string(name) : "unknown";
}

std::string compiler() {
#if defined(__clang__)
  return "clang " __clang_version__;
#elif defined(__GNUC__)
  return "GCC " __VERSION__;
#else
  return "unknown";
#endif
}

}  // namespace

std::string provenance_json(const Provenance& p) {
  nlohmann::json j;
  j["command"] = p.command;
  j["ranks"] = ranks::size();
  j["threads_per_rank"] = p.threads;
  j["commit"] = STEPWISE_COMMIT;
  j["compiler"] = compiler();
  j["libraries"] = {
      {"sundials", SUNDIALS_VERSION},
      {"gsl", GSL_VERSION},
      {"fftw", PeriodicFft::library_version()},
      {"eigen", fmt::format("{}.{}.{}", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION)},
      {"boost", fmt::format("{}.{}.{}", BOOST_VERSION / 100000, BOOST_VERSION / 100 % 1000, BOOST_VERSION % 100)},
      {"suitesparse", fmt::format("{}.{}.{}", SUITESPARSE_MAIN_VERSION, SUITESPARSE_SUB_VERSION, SUITESPARSE_SUBSUB_VERSION)},
      {"mpi", ranks::library_version()},
  };
  j["machine"] = {{"host", host()}, {"cpu", cpu_model()}, {"cores", std::max(1u, std::thread::hardware_concurrency())}};
  if (p.slowness > 0) j["machine"]["slowness"] = p.slowness;
  j["start"] = utc(p.start);
  j["end"] = utc(p.end);
  j["seconds"] = std::chrono::duration<double>(p.end - p.start).count();
  j["rank_busy_seconds"] = p.rank_seconds;
  // how evenly the ranks shared the sweeps: the busiest rank's seconds over the mean (1 is perfect)
  if (!p.rank_seconds.empty()) {
    const double mean = std::accumulate(p.rank_seconds.begin(), p.rank_seconds.end(), 0.0) / static_cast<double>(p.rank_seconds.size());
    j["rank_busiest_over_mean"] = mean > 0 ? *std::max_element(p.rank_seconds.begin(), p.rank_seconds.end()) / mean : 1.0;
  }
  return j.dump(2) + "\n";
}

}  // namespace stepwise
