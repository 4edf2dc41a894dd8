#pragma once
/// Number formatting of diagnostics and summaries, one home for fast/ and the
/// CLI (fast/src/numerics/format.cpp). Error, warning and summary texts are
/// compared by tests, so each format is fixed here.
#include <cstddef>
#include <string>

namespace fdsid {

/// x in the ostream default (%g-like) notation with `digits` significant
/// digits, as `std::ostringstream s; s.precision(digits); s << x;` prints it
/// (e.g. fmt(1e-8, 4) == "1e-08", fmt(0.125, 2) == "0.12").
std::string fmt(double x, int digits);

/// x in scientific notation with `digits` digits after the point, as
/// printf("%.*e", digits, x) prints it (e.g. sci(1234.56, 3) == "1.235e+03").
std::string sci(double x, int digits = 3);

/// A p-value as sci(p, digits), or "< 1e-300" below the smallest normal
/// double (it underflowed; review finding 21: not 0).
std::string p_text(double p, int digits = 3);
/// "= " + p_text(p) for a normal p, else "< 1e-300": after "p " in a sentence
/// ("p = 7.42e-02", "p < 1e-300"; a user review: "p = 0.00e+00" was printed).
std::string p_relation(double p, int digits = 3);

/// Relative error estimates at or below this say nothing: six or more correct
/// digits, more than the summaries print.
constexpr double kPrecisionWarningLevel = 1e-6;

/// How a relative error estimate was obtained: u × a condition number (a
/// first-order bound) or by rounding-size perturbations (a statistical estimate).
enum class PrecisionEstimate { FirstOrderBound, Statistical };

/// The precision verdict of an estimate whose relative error estimate is
/// `estimate` (review finding 38: a warning must say whether the model is
/// usable). "" when estimate ≤ kPrecisionWarningLevel; below 1 "usable to about d
/// significant digits", d = ⌊−log10 estimate⌋ (said to be a bound, often
/// pessimistic, or a statistical estimate, as `kind` says), "its order of
/// magnitude" for d = 0; 1 or more, or not finite, "UNUSABLE …": no digit is
/// certain. `what` names the quantity and `details` the condition numbers;
/// `advice` is what the user can do: compare with it (usable) or use it
/// instead (unusable).
struct PrecisionAdvice {
  std::string compare = "compare with --precision high";
  std::string instead = "use --precision high, a lower order or another r";
};
std::string precision_warning(double estimate, const std::string& what, const std::string& details,
                              PrecisionEstimate kind = PrecisionEstimate::FirstOrderBound,
                              const PrecisionAdvice& advice = {});

/// The correct digits a relative error estimate in (0, 1) leaves, as the
/// precision verdicts say them: "d significant digit(s)", d = ⌊−log10 estimate⌋,
/// or "its order of magnitude" for d = 0.
std::string significant_digits_text(double estimate);

/// Whether an estimate with this relative error estimate has a correct digit (< 1).
inline bool usable_precision(double estimate) { return estimate < 1.0; }

/// Levenshtein distance (insertions, deletions, substitutions): how messages
/// name a misspelt option or field (the CLI's unknown options, a meta's keys).
size_t edit_distance(const std::string& a, const std::string& b);

}  // namespace fdsid
