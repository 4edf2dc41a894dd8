#pragma once
/// The figures of `fdsid ... --plot FILE`: which quantities of fast/'s results
/// go on which axes. Each builder only arranges numbers it is given (and
/// evaluates the identified model on a dense grid); render() in plot.hpp draws.
#include <vector>

#include "fdsid/frf_id.hpp"
#include "fdsid/gap.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/plot.hpp"
#include "fdsid/spectrum_id.hpp"

namespace fdsid::plot {

/// Poles (×) and zeros (○) of a model: the unit circle for discrete time, the
/// imaginary axis for continuous time, with room above the map for the legend
/// (review finding 41). The last panel of the identification figures.
Panel pole_zero_panel(const StateSpace& model);

/// Akçay (2011) Table 1: σ_k of Van Overschee's Ĝ_9F_8 (Eq. 13) and of Akçay's
/// 𝒴 (Eq. 19) against M, log–log, beside the rounding level u·σ_1.
Figure table1_figure(const std::vector<Table1Row>& rows);

/// Akçay (2011) Table 2: mean L2/L∞ errors against M (log–log) with the
/// 10–90 % spread over the realisations, and the share of vo1997 runs that
/// failed (at step 6 and elsewhere) beside Algorithm 1's failures.
Figure table2_figure(const std::vector<Table2Row>& rows, const Table2Options& options);

/// Pintelon (2002) Fig. 1b / 2b: std ratio across frequency with Eq. (28) and
/// the bound of Eq. (30); the three standard deviations themselves beside it.
Figure std_ratio_figure(const FigureResult& result, int figure, const FigureOptions& options);

/// identify-spectrum: data and identified spectrum, the relative residual on
/// the grid, the singular values with the order read marked, poles and zeros
/// in the z-plane with the unit circle.
Figure spectrum_figure(const SpectrumData& data, const SpectrumResult& result);

/// identify-frf: |G| of the data and of the model, the residual beside the
/// noise standard deviation, the singular values of step 1c with the order
/// marked, poles and zeros (z-plane with unit circle, or s-plane).
/// `magnitude_sd` (optional, one p × m matrix per frequency): the standard
/// deviation of |G| of a refined model, drawn as 2σ on the residual panel.
Figure frf_figure(const FrfData& data, const FrfResult& result,
                  const std::vector<Eigen::MatrixXd>* magnitude_sd = nullptr);

/// gap: t(k) across frequency for the model as given and after each added
/// stage, the noise floor E t = 1 and the per-line critical value, the flagged
/// bands; and the gap each candidate effect leaves alone.
Figure gap_figure(const GapReport& report, int periods);

}  // namespace fdsid::plot
