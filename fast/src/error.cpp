#include "fdsid/error.hpp"

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace fdsid {

const char* to_string(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::Input: return "input";
    case ErrorKind::Grid: return "grid";
    case ErrorKind::Dimension: return "dimension";
    case ErrorKind::Order: return "order";
    case ErrorKind::Split: return "split";
    case ErrorKind::Positivity: return "positivity";
    case ErrorKind::Riccati: return "riccati";
    case ErrorKind::Numerical: return "numerical";
    case ErrorKind::Resource: return "resource";
  }
  return "unknown";
}

Error::Error(ErrorKind kind, std::string where, const std::string& message)
    : std::runtime_error(where + ": " + message), kind_(kind), where_(std::move(where)), message_(message) {}

double available_memory_bytes() {
  std::ifstream f("/proc/meminfo");
  std::string key;
  double kib = 0;
  std::string unit;
  while (f >> key >> kib >> unit)
    if (key == "MemAvailable:") return kib * 1024.0;
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? double(pages) * double(page) : 0.0;
}

void require_memory(double bytes, const std::string& where, const std::string& what) {
  const double avail = available_memory_bytes();
  if (avail > 0 && bytes > 0.8 * avail) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%s needs about %.0f MiB, more than 80%% of the %.0f MiB this machine has available",
                  what.c_str(), bytes / 1048576.0, avail / 1048576.0);
    throw Error(ErrorKind::Resource, where, buf);
  }
}

}  // namespace fdsid
