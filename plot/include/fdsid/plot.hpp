#pragma once
/// Figures of fdsid: a small description of a figure (panels of series, bands
/// and reference lines) and its rendering with PLplot.
///
/// Why PLplot (C++ API, Debian libplplot-dev + plplot-driver-cairo): it draws
/// in-process, so `--plot` needs no external program at run time (gnuplot
/// through gnuplot-iostream would need the gnuplot binary on every machine
/// that runs fdsid and a pipe to it), and it writes both formats we need:
/// SVG through its own svg driver (text stays text, so tests can read the
/// labels) and PNG through the cairo driver (antialiased).
///
/// The figures themselves (which quantity on which axis) are built in
/// figures.hpp from the results of fast/; this file knows nothing of the papers.
#include <array>
#include <string>
#include <utility>
#include <vector>

namespace fdsid::plot {

/// Colours of the palette (PLplot cmap0 indices set by render()).
enum Colour : int { Black = 1, Blue, Orange, Green, Red, Purple, Brown, Pink, Grey, Olive, Cyan, Shade, ShadeRed };

struct Series {
  std::string label;          ///< legend text (PLplot escapes allowed: #gs = σ, #d/#u sub/superscript); empty: no entry
  std::vector<double> x, y;
  Colour colour = Blue;
  bool line = true;           ///< join the points (a non-finite or, on a log axis, non-positive point breaks the line)
  std::string symbol;         ///< marker drawn at each point (UTF-8, e.g. "×", "○", "•"); empty: none
  bool dashed = false;
  /// Line width in PLplot's units; 0: the default 1.6. A wide pale line under a
  /// thin one keeps both visible where they coincide (review finding 46).
  double width = 0;
  /// Optional vertical error bars: y_low[i] .. y_high[i] (same length as y).
  std::vector<double> y_low, y_high;
};

/// A shaded vertical band x0 .. x1 (e.g. frequencies a test flagged).
struct Band {
  double x0 = 0, x1 = 0;
  Colour colour = ShadeRed;
};

struct Text {
  double x = 0, y = 0;        ///< data coordinates
  std::string text;
  Colour colour = Black;
  bool vertical = false;      ///< written upwards from (x, y)
};

struct Axis {
  std::string label;          ///< with units
  bool log = false;
  double min = 0, max = 0;    ///< min < max fixes the range; else it is read off the data
  /// Room above the data for a legend placed at the top (ignored when the
  /// range is fixed): decades on a log axis, a multiple of the data span on a
  /// linear one.
  double headroom = 0;
  /// Category names: ticks at 1 … n labelled with them instead of numbers
  /// (x axis, linear only).
  std::vector<std::string> categories;
  /// An index axis (x, linear): ticks only at whole numbers (review finding
  /// 49: 1.0, 1.5, 2.0 … on the singular values' index axis).
  bool integer = false;
};

inline Axis axis(std::string label, bool log = false, double min = 0, double max = 0) {
  Axis a;
  a.label = std::move(label);
  a.log = log;
  a.min = min;
  a.max = max;
  return a;
}

enum class LegendAt { TopRight, TopLeft, BottomRight, BottomLeft, None };

struct Panel {
  std::string title;
  Axis x, y;
  std::vector<Series> series;
  std::vector<Band> bands;
  std::string band_label;     ///< legend entry of the bands (empty: none)
  std::vector<Text> texts;
  /// The preferred corner of the legend; render() moves it to the corner holding the fewest data (ties keep it).
  LegendAt legend = LegendAt::TopRight;
  bool equal_aspect = false;  ///< one unit on x as long as one on y (pole-zero maps)
};

struct Figure {
  std::vector<Panel> panels;
  int columns = 1;            ///< panels fill rows of this many
  int width = 1100, height = 0;  ///< pixels; height 0: 420 per row of panels
};

/// Draws `fig` into `path`: SVG (".svg") or PNG (".png"), chosen by the
/// extension. Written to a temporary file in the same directory and renamed,
/// so an existing file is replaced only by a complete figure. Throws
/// fdsid::Error(Input, "--plot", ...) for another extension, an unwritable
/// path or a figure without panels, and Error(Numerical, "plot", ...) when
/// PLplot fails. Not thread-safe (PLplot keeps global state): call it from one
/// thread at a time.
void render(const Figure& fig, const std::string& path);

/// The world window [x0, x1, y0, y1] render() draws the panel in (log10 of a
/// log axis): the data's range padded by 4 %, the axis headroom added, and for
/// an equal-aspect panel squared about its centre.
std::array<double, 4> panel_window(const Panel& p);

/// Where render() puts a panel's legend of `entries` lines in the window
/// [x0, x1] × [y0, y1] (world coordinates: log10 of a log axis): the
/// preferred corner unless another holds fewer data points (review finding
/// 41). Each corner is a box of 10 % + 0.65 % per character of the longest
/// label (≤ 90 %) of the width and entries × 8 % + 4 % (≤ 70 %) of the height; along a drawn line the segments' midpoints count
/// too; a marker weighs 20 line points.
LegendAt legend_corner(const Panel& p, int entries, double x0, double x1, double y0, double y1);
/// Checks that `path` ends in .svg or .png (case-insensitive) before any work
/// is done; throws Error(Input, "--plot", ...) otherwise.
void check_plot_path(const std::string& path);

}  // namespace fdsid::plot
