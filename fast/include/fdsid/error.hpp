#pragma once
/// Typed errors of the fdsid library.
///
/// Purpose: every failure of fast/ says which step failed, on which input, and
/// with which number, so that a program embedding the library can react and the
/// command-line tool can print one clear line and exit with status 2.
#include <stdexcept>
#include <string>

namespace fdsid {

/// What kind of failure an Error reports.
enum class ErrorKind {
  Input,       ///< a file or field is missing, malformed, NaN/Inf or of the wrong shape
  Grid,        ///< the frequency grid is not one the method can use
  Dimension,   ///< p, r, n, M violate the method's inequalities
  Order,       ///< the model order cannot be determined or is not supported
  Split,       ///< Akçay (2011) step 6: no clean stable/antistable split
  Positivity,  ///< spectrum data or estimate not positive, or E - C P C^T not positive definite
  Riccati,     ///< step 9: the Riccati equation has no stabilising solution
  Numerical,   ///< any other numerical breakdown
  Resource     ///< the input would need more memory (or work) than fdsid allows; refused before allocating
};

/// Short lower-case name of an ErrorKind ("split", "positivity", ...).
const char* to_string(ErrorKind kind);

/// The one exception type thrown by fast/. what() is a single line:
/// "<where>: <message>", where <where> names the step or the input.
class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, std::string where, const std::string& message);
  ErrorKind kind() const noexcept { return kind_; }
  /// The step ("step 6") or the input ("spectrum.csv line 12") that failed.
  const std::string& where() const noexcept { return where_; }
  /// What is wrong, without the location.
  const std::string& message() const noexcept { return message_; }
  /// The same error located inside `outer` (e.g. the data file a step ran on).
  Error within(const std::string& outer) const { return Error(kind_, outer + ": " + where_, message_); }

 private:
  ErrorKind kind_;
  std::string where_;
  std::string message_;
};

/// Memory the machine can still give (MemAvailable of /proc/meminfo, else
/// physical memory via sysconf), in bytes; 0 when unknown.
double available_memory_bytes();

/// Throws Error(Resource) at `where` when `bytes` exceed 80 % of
/// available_memory_bytes(), naming both figures in MiB and `what` needs them.
/// Called before the large allocations, so an oversized input is refused
/// instead of crashing the process.
void require_memory(double bytes, const std::string& where, const std::string& what);

}  // namespace fdsid
