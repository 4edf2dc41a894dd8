// fdsid conformance over the certified suite (fixtures/certified): fdsid's own
// identify-spectrum / identify-frf pass every case; deliberately wrong
// candidates (a mislabelled p or r, a model of another system) fail theirs; a candidate that crashes, hangs
// or writes no valid JSON fails its case, never the runner (exit 1, not 2).
#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <tuple>

#include <nlohmann/json.hpp>

#include "cli_harness.hpp"

namespace {

using fdsid::cli_harness::describe;
using fdsid::cli_harness::IsBadInput;
using fdsid::cli_harness::kExe;
using fdsid::cli_harness::run_fdsid;
using fdsid::cli_harness::RunResult;
using nlohmann::json;
namespace fs = std::filesystem;

const std::string kSuite = std::string(FDSID_SOURCE_DIR) + "/fixtures/certified";

class Conformance : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    std::random_device rd;
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("fdsid-conformance-" + std::string(info->name()) + "-" +
                                        std::to_string(getpid()) + "-" + std::to_string(counter++) + "-" +
                                        std::to_string(rd()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  json read_json(const std::string& name) const {
    std::ifstream f(path(name));
    return json::parse(f);
  }
  std::string read_text(const std::string& name) const {
    std::ifstream f(path(name));
    return std::string(std::istreambuf_iterator<char>(f), {});
  }
  // The report's entry of one case.
  static const json& entry(const json& report, const std::string& name) {
    for (const auto& c : report["cases"])
      if (c["case"] == name) return c;
    static const json none;
    return none;
  }
  fs::path dir_;
};

std::size_t manifest_cases() {
  std::ifstream f(kSuite + "/cases.json");
  return json::parse(f)["cases"].size();
}

TEST_F(Conformance, FdsidPassesEveryCertifiedCase) {
  const RunResult r = run_fdsid({"conformance", "--suite", kSuite, "--candidate", kExe + " {fdsid_args} --json {out}",
                                 "--json", path("report.json"), "--junit", path("report.xml")});
  ASSERT_EQ(r.status, 0) << describe(r);
  const json report = read_json("report.json");
  EXPECT_EQ(report["total"].get<std::size_t>(), manifest_cases());
  EXPECT_EQ(report["failed"], 0);
  EXPECT_TRUE(report["all_pass"].get<bool>());
  std::set<std::string> tiers;
  for (const auto& c : report["cases"]) {
    tiers.insert(c["tier"].get<std::string>());
    // Every case certifies its poles, and fdsid reproduces at least one
    // digit of them: a pass with LRE 0 would mean the scoring saw nothing.
    bool poles = false;
    for (const auto& q : c["lre"])
      if (q["name"] == "poles") {
        poles = true;
        EXPECT_GT(q["certified_digits"].get<int>(), 15) << c["case"];
        EXPECT_GE(q["lre"].get<double>(), 1.0) << c["case"];
      }
    EXPECT_TRUE(poles) << c["case"];
  }
  EXPECT_EQ(tiers, (std::set<std::string>{"lower", "average", "higher"}));
  const std::string xml = read_text("report.xml");
  EXPECT_NE(xml.find("tests=\"" + std::to_string(manifest_cases()) + "\" failures=\"0\""), std::string::npos) << xml;
  EXPECT_NE(r.out.find(std::to_string(manifest_cases()) + " of " + std::to_string(manifest_cases()) +
                       " certified cases pass"),
            std::string::npos)
      << r.out;
}

TEST_F(Conformance, ClassicMistakesFailTheirCases) {
  // Two mislabelled settings on noisy data, where they change the estimate: a
  // spectral factor computed with p = 12 for a case certified at p = 9, and
  // an FRF estimate made with r = 10 for a case certified at r = 8.
  const RunResult r = run_fdsid(
      {"conformance", "--suite", kSuite, "--case", "akcay2011_M256_noisy", "--case",
       "frf_pintelon2002_F40_discrete_noisy", "--candidate-spectrum",
       kExe + " identify-spectrum --data {data} --order {order} --p 12 --r {r} --json {out}",
       "--candidate-frf", kExe + " identify-frf --frf {frf} --order {order} --r 10 --json {out}", "--json",
       path("report.json")});
  ASSERT_EQ(r.status, 1) << describe(r);
  const json report = read_json("report.json");
  EXPECT_EQ(report["failed"], 2);
  for (const char* name : {"akcay2011_M256_noisy", "frf_pintelon2002_F40_discrete_noisy"}) {
    const json& c = entry(report, name);
    EXPECT_FALSE(c["pass"].get<bool>()) << name;
    EXPECT_NE(c["verdict"].get<std::string>().find("DISAGREES"), std::string::npos) << c["verdict"];
    EXPECT_EQ(c["exit_status"], 0);
  }
}

TEST_F(Conformance, ABrokenCandidateFailsItsCaseNotTheRunner) {
  struct Broken {
    std::string command, reason;
  };
  const std::vector<Broken> broken = {
      {"kill -SEGV $$", "killed by signal 11"},
      {"sleep 20", "ran past --timeout"},
      {"echo not-json > {out}", "is not JSON"},
      {"true", "wrote no model JSON"},
      {"echo '{\"A\": 1}' > {out}", "is not a model"},
      {"echo oops >&2; exit 3", "exited 3"},
  };
  for (const Broken& b : broken) {
    const RunResult r = run_fdsid({"conformance", "--suite", kSuite, "--case", "akcay2011_M64", "--timeout", "2",
                                   "--candidate", b.command, "--json", path("report.json")});
    ASSERT_EQ(r.status, 1) << b.command << "\n" << describe(r);
    const json report = read_json("report.json");
    const json& c = entry(report, "akcay2011_M64");
    EXPECT_FALSE(c["pass"].get<bool>());
    EXPECT_NE(c["verdict"].get<std::string>().find(b.reason), std::string::npos) << b.command << ": " << c["verdict"];
  }
  // The stderr excerpt comes with a failed case.
  const RunResult r = run_fdsid({"conformance", "--suite", kSuite, "--case", "akcay2011_M64", "--candidate",
                                 "echo 'my solver diverged' >&2; exit 1"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("stderr: my solver diverged"), std::string::npos) << r.out;
}

TEST_F(Conformance, TheTrueSystemPassesANoiseFreeCaseAndFailsAnotherSystemsCase) {
  // Noise-free samples of the Akçay (2011) system identify that system
  // exactly (Theorem 1), so its own model file is a correct answer; given for
  // the Pintelon (2002) FRF of another plant's data it is not.
  const std::string model = kSuite + "/systems/akcay2011.json";
  const RunResult r = run_fdsid({"conformance", "--suite", kSuite, "--case", "akcay2011_M64", "--case",
                                 "frf_continuous4_F50_bilinear", "--candidate", "cp " + model + " {out}", "--json",
                                 path("report.json")});
  ASSERT_EQ(r.status, 1) << describe(r);
  const json report = read_json("report.json");
  EXPECT_TRUE(entry(report, "akcay2011_M64")["pass"].get<bool>()) << entry(report, "akcay2011_M64");
  // The certified exact factor is this system's normalised factor: the
  // system read in double agrees with it to the rounding of its parameters,
  // relative error <= 10 n u / (1 - rho) = 10 * 4 * 1.1e-16 / (1 - 0.954) =
  // 9.6e-14 (rho the largest pole modulus; the resolvent's sensitivity), an
  // LRE >= 13.0; 12 leaves a factor 10. A factor not normalised by D's polar
  // factor, or not minimum phase, scores near 0.
  bool exact = false;
  for (const auto& q : entry(report, "akcay2011_M64")["lre"])
    if (q["name"] == "exact_factor") {
      exact = true;
      EXPECT_GE(q["lre"].get<double>(), 12.0) << q;
      EXPECT_EQ(q["certified_digits"], 40);
    }
  EXPECT_TRUE(exact) << "the noise-free spectrum case certifies no exact factor";
  EXPECT_FALSE(entry(report, "frf_continuous4_F50_bilinear")["pass"].get<bool>());
  EXPECT_NE(entry(report, "frf_continuous4_F50_bilinear")["verdict"].get<std::string>().find("discrete-time"),
            std::string::npos);
  // A user review: that FAIL row printed LRE scores like a pass's (the
  // discrete matrices evaluated on the continuous case's axis): no scores now.
  EXPECT_TRUE(entry(report, "frf_continuous4_F50_bilinear")["lre"].empty())
      << entry(report, "frf_continuous4_F50_bilinear")["lre"];
}

// A user review: a candidate writing "sample_time": 0.001 for every case
// passed without a note (the lines are per sample, so Ts was overwritten by
// the case's). The true system with a wrong sample time fails, named.
TEST_F(Conformance, AWrongSampleTimeFailsItsCase) {
  const std::string model = kSuite + "/systems/akcay2011.json";
  const RunResult r =
      run_fdsid({"conformance", "--suite", kSuite, "--case", "akcay2011_M64", "--candidate",
                 "sed 's/\"sample_time\": 1.0/\"sample_time\": 0.001/' " + model + " > {out}", "--json",
                 path("report.json")});
  ASSERT_EQ(r.status, 1) << describe(r);
  const json report = read_json("report.json");
  const json& c = entry(report, "akcay2011_M64");
  EXPECT_FALSE(c["pass"].get<bool>());
  EXPECT_NE(c["verdict"].get<std::string>().find("has sample_time 0.001 s; the case's is 1 s"), std::string::npos)
      << c["verdict"];
}

TEST_F(Conformance, BadInputIsRefusedBeforeAnyCandidateRuns) {
  const std::string marker = path("ran");
  const std::string cand = "touch " + marker + "; " + kExe + " {fdsid_args} --json {out}";
  EXPECT_TRUE(IsBadInput(run_fdsid({"conformance", "--suite", kSuite}), {"--candidate"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"conformance", "--suite", kSuite, "--candidate", cand + " {bogus}"}),
                         {"unknown placeholder {bogus}"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"conformance", "--suite", kSuite, "--case", "nope", "--candidate", cand}),
                         {"--case", "nope"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"conformance", "--suite", kSuite, "--tier", "hard", "--candidate", cand}),
                         {"--tier", "hard"}));
  // A certified case whose inputs no longer match the manifest is named, with the fix.
  const fs::path copy = dir_ / "suite";
  fs::copy(kSuite, copy, fs::copy_options::recursive);
  json manifest;
  {
    std::ifstream f(copy / "cases.json");
    manifest = json::parse(f);
  }
  manifest["cases"][0]["order"] = manifest["cases"][0]["order"].get<int>() + 1;
  std::ofstream(copy / "cases.json") << manifest.dump(1);
  EXPECT_TRUE(IsBadInput(run_fdsid({"conformance", "--suite", copy.string(), "--candidate", cand}),
                         {"differ from cases.json", "scripts/certify.sh"}));
  // So is one certified with another line rule (Eq. 34's min_input_snr
  // changes the lines an eiv case keeps, hence its certified values).
  manifest["cases"][0]["order"] = manifest["cases"][0]["order"].get<int>() - 1;
  const auto eiv = std::find_if(manifest["cases"].begin(), manifest["cases"].end(),
                                [](const json& c) { return c.value("treatment", "") == "eiv"; });
  ASSERT_NE(eiv, manifest["cases"].end()) << "the suite has no errors-in-variables case";
  (*eiv)["min_input_snr"] = 20;
  std::ofstream(copy / "cases.json") << manifest.dump(1);
  EXPECT_TRUE(IsBadInput(run_fdsid({"conformance", "--suite", copy.string(), "--candidate", cand}),
                         {"differ from cases.json", std::string(eiv->at("case"))}));
  eiv->erase("min_input_snr");
  // A misspelt setting in the manifest is named with the values it takes, never read as the default
  // (an "eiv_variance" other than "model" was taken as "data"); a setting of
  // errors-in-variables on a case without it is refused, never ignored.
  for (const auto& [field, value, refusal] : {std::tuple<std::string, std::string, std::string>{
                                                  "eiv_variance", "modle", "use data or model"},
                                              {"domain", "Discrete", "use discrete or continuous"},
                                              {"treatment", "EIV", "use plain or eiv"},
                                              {"kind", "FRF", "use spectrum, frf or records"},
                                              {"eiv_variance", "model", "applies to \"treatment\": \"eiv\" only"}}) {
    json bad = manifest;
    bad["cases"][0][field] = value;
    std::ofstream(copy / "cases.json") << bad.dump(1);
    EXPECT_TRUE(IsBadInput(run_fdsid({"conformance", "--suite", copy.string(), "--candidate", cand}),
                           {"field \"" + field + "\"", refusal}));
  }
  // A required setting left out is named as missing, with the values it takes.
  json no_kind = manifest;
  no_kind["cases"][0].erase("kind");
  std::ofstream(copy / "cases.json") << no_kind.dump(1);
  EXPECT_TRUE(IsBadInput(run_fdsid({"conformance", "--suite", copy.string(), "--candidate", cand}),
                         {"has no \"kind\"", "use spectrum, frf or records"}));
  EXPECT_FALSE(fs::exists(marker)) << "a candidate ran although the input was bad";
}

}  // namespace
