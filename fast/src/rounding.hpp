#pragma once
// The rounding's effect on what an estimate is used for — G on the data's
// frequencies and the poles — by statistical condition estimation (internal
// header; identify-frf's subspace estimate and the ML refinement).
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "fdsid/format.hpp"
#include "fdsid/model.hpp"

namespace fdsid {

/// Random directions per estimate: the largest of 3 draws (measured against
/// the 50-digit reference: 2–22 × the distance, never below it, in the
/// tests and on the F-16 and Silverbox records; README).
constexpr int kRoundingSamples = 3;

/// Purpose: the largest relative change, over the moved models added, of Ĝ on
/// the data's frequencies (‖ΔG‖_F / ‖G‖_F, all channels) and of each pole
/// (|Δλ|/|λ|, |Δλ| for λ = 0; poles matched closest pair first, since a pole
/// set by rounding can land beside a determined one). A pole that moves by its
/// own size or more is "set by rounding, not by the data".
/// Method: the caller moves its inputs by their rounding's size in random
/// directions, recomputes, and adds each moved model (Kenney & Laub 1994).
/// An estimate of the typical error, not a bound.
class RoundingEffect {
 public:
  RoundingEffect(const StateSpace& base, const Eigen::VectorXd& omega);
  /// Measures one moved model against the base.
  void add(const StateSpace& moved);
  /// A moved estimate failed where the base did not: nothing is determined
  /// (g and poles infinite); `why` names the step.
  void fail(const std::string& why);

  double g = 0;         ///< relative error of Ĝ on the data's frequencies
  double poles = 0;     ///< the largest relative pole error
  std::string failure;  ///< why a moved estimate failed, or ""
  /// The base poles whose error is 1 or more.
  std::vector<cplx> undetermined() const;

 private:
  Eigen::VectorXd omega_;
  std::vector<Eigen::MatrixXcd> G0_;
  double g0_ = 0;
  Eigen::VectorXcd base_poles_;
  std::vector<double> pole_error_;
};

/// The precision warning for a rounding effect ("" when both errors are at or
/// below kPrecisionWarningLevel), naming the poles set by rounding. `moves`
/// says what was moved ("step 1b's R and step 1c's C_Y"), `bound` the
/// first-order bound kept beside it ("A's entries in the estimate's basis:
/// bound 13.8"), `advice` what the user can do.
std::string rounding_warning(const RoundingEffect& e, const std::string& moves, const std::string& bound,
                             const PrecisionAdvice& advice = {});

}  // namespace fdsid
