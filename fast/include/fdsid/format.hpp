#pragma once
/// Number formatting of diagnostics and summaries, one home for fast/ and the
/// CLI (fast/src/numerics/format.cpp). Error, warning and summary texts are
/// compared by tests, so each format is fixed here.
#include <string>

namespace fdsid {

/// x in the ostream default (%g-like) notation with `digits` significant
/// digits, as `std::ostringstream s; s.precision(digits); s << x;` prints it
/// (e.g. fmt(1e-8, 4) == "1e-08", fmt(0.125, 2) == "0.12").
std::string fmt(double x, int digits);

/// x in scientific notation with `digits` digits after the point, as
/// printf("%.*e", digits, x) prints it (e.g. sci(1234.56, 3) == "1.235e+03").
std::string sci(double x, int digits = 3);

}  // namespace fdsid
