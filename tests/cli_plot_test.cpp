// Command-line tests of --plot (every command that draws a figure) and of the
// progress lines of the long runs (on a terminal only).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include "cli_harness.hpp"
#include "svg_text.hpp"

namespace fs = std::filesystem;
using namespace fdsid::cli_harness;

namespace {

const std::string kSource = FDSID_SOURCE_DIR;

class CliPlot : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    dir_ = fs::temp_directory_path() / ("fdsid_cli_plot_" + std::to_string(rd()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // Runs the command with --plot FILE.svg; expects success and every label.
  void expect_figure(std::vector<std::string> args, const std::string& name,
                     std::initializer_list<std::string> labels) {
    const std::string out = path(name + ".svg");
    args.insert(args.end(), {"--plot", out});
    const RunResult r = run_fdsid(args, 300);
    ASSERT_TRUE(Succeeded(r));
    ASSERT_TRUE(fs::exists(out)) << describe(r);
    const std::string text = fdsid::testing::svg_file_text(out);
    for (const std::string& l : labels) EXPECT_NE(text.find(l), std::string::npos) << name << ": no \"" << l << "\"";
  }

  // Periodic records of the Pintelon (2002) plant with white output noise.
  void records(const std::string& csv, const std::string& meta) {
    ASSERT_TRUE(Succeeded(run_fdsid({"simulate-records", "--model", kSource + "/fixtures/systems/pintelon2002.json",
                                     "--period", "256", "--periods", "6", "--noise-std", "0.01", "--seed", "3",
                                     "--out", csv, "--meta-out", meta})));
  }

  fs::path dir_;
};

TEST_F(CliPlot, ReproductionsDrawTheirFigures) {
  expect_figure({"reproduce", "table1"}, "table1", {"M (grid intervals", "singular value", "Van Overschee"});
  expect_figure({"reproduce", "table2", "--realizations", "3", "--M", "200", "400", "--threads", "1"}, "table2",
                {"error of the identified spectrum", "share of runs that failed", "step 6"});
  expect_figure({"reproduce", "fig1", "--runs", "20", "--threads", "1"}, "fig1",
                {"frequency f/f", "Monte Carlo ratio", "Eq. (28)", "Eq. (30)"});
  expect_figure({"reproduce", "fig2", "--runs", "20", "--threads", "1"}, "fig2",
                {"frequency f/f", "Monte Carlo ratio", "Eq. (30)"});
}

TEST_F(CliPlot, IdentificationsDrawDataModelSingularValuesAndPoles) {
  expect_figure({"identify-spectrum", "--data", kSource + "/data/akcay2011_M1000_eps1e-3.csv"}, "spectrum",
                {"identified", "relative residual", "index k", "order read", "unit circle", "poles", "zeros"});
  const std::string csv = path("rec.csv"), meta = path("rec.json");
  records(csv, meta);
  expect_figure({"identify-frf", "--data", csv, "--meta", meta}, "frf",
                {"frequency (cycles/sample)", "|G|", "noise std", "order n = 4", "unit circle"});
}

TEST_F(CliPlot, GapDrawsTheResidualAndTheCandidates) {
  const std::string csv = path("rec.csv"), meta = path("rec.json");
  records(csv, meta);
  expect_figure({"gap", "--model", kSource + "/fixtures/systems/pintelon2002.json", "--data", csv, "--meta", meta},
                "gap", {"t(k)", "noise floor", "quantile of F(2, 2M-2)", "gain_error", "candidate effect"});
}

TEST_F(CliPlot, BadPlotPathsAreRefusedBeforeAnyWork) {
  const std::string data = kSource + "/data/akcay2011_M1000_eps1e-3.csv";
  EXPECT_TRUE(IsBadInput(run_fdsid({"reproduce", "table1", "--plot", path("t.pdf")}), {"--plot", ".svg or .png"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"reproduce", "table1", "--plot", ""}), {"--plot"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"reproduce", "table1", "--plot", path("no/such/dir/t.svg")}),
                         {"--plot", "does not exist"}));
  // A Monte Carlo run is refused at once, not after its minutes of work.
  EXPECT_TRUE(IsBadInput(run_fdsid({"reproduce", "table2", "--plot", path("t2.gif")}, 10), {"--plot"}));
  // Never over an input.
  const std::string copy = path("data.svg");
  fs::copy_file(data, copy);
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-spectrum", "--data", copy, "--plot", copy}), {"--plot", "input"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-spectrum", "--data", data, "--precision", "high", "--plot",
                                    path("h.svg")}),
                         {"--plot", "double-precision"}));
  EXPECT_FALSE(fs::exists(path("h.svg")));
  // Review finding 6: the summary was printed and --json written before the
  // --plot folder was found missing; --json paths were not checked at all.
  const RunResult both = run_fdsid({"identify-spectrum", "--data", data, "--plot", path("nodir/out.png"), "--json",
                                    path("j.json")});
  EXPECT_TRUE(IsBadInput(both, {"--plot", "nodir", "does not exist"}));
  EXPECT_EQ(both.out, "");
  EXPECT_FALSE(fs::exists(path("j.json")));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-spectrum", "--data", data, "--json", path("nodir/j.json")}),
                         {"--json", "does not exist"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-spectrum", "--data", data, "--json", dir_.string()}),
                         {"--json", "is a folder"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"reproduce", "table2", "--json", path("nodir/t2.json")}, 10), {"--json"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"sample-spectrum", "--model", kSource + "/fixtures/systems/akcay2011.json", "--M",
                                    "8", "--out", path("nodir/s.csv")}),
                         {"--out", "does not exist"}));
}

TEST_F(CliPlot, ProgressOnlyOnATerminal) {
  // Through pipes (as here): nothing on stderr.
  const RunResult quiet = run_fdsid({"reproduce", "table2", "--realizations", "3", "--M", "200", "--vo-epsilon", "0"});
  ASSERT_TRUE(Succeeded(quiet));
  EXPECT_EQ(quiet.err, "");
  // On a pseudo-terminal (util-linux `script`), the count of realisations.
  ASSERT_EQ(std::system("command -v script >/dev/null 2>&1"), 0)
      << "util-linux `script` (Debian package bsdutils, installed by scripts/install-deps.sh) provides the terminal";
  const RunResult tty = run_fdsid_via_script({"reproduce", "table2", "--realizations", "3", "--M", "200",
                                              "--vo-epsilon", "0"});
  ASSERT_TRUE(Succeeded(tty));
  EXPECT_NE(tty.out.find("table2: realisations: 3/3"), std::string::npos) << describe(tty);
}

}  // namespace
