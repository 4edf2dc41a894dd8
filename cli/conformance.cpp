// fdsid conformance: another implementation's command run over the certified
// suite (fixtures/certified), each model it writes scored as `check` would
// judge it (fdsid/certified.hpp). A candidate that crashes, hangs or writes
// no valid model fails its case; the runner itself exits 2 only for bad input.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <thread>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include "common.hpp"
#include "fdsid/certified.hpp"
#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "fdsid/io.hpp"

namespace fdsid::cli {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

struct ConformanceCommand {
  std::string suite = "fixtures/certified";
  std::string candidate, candidate_spectrum, candidate_frf;
  std::vector<std::string> tiers, cases;
  double timeout = 120;
  std::string json_path, junit_path, work;
};

const std::set<std::string> kPlaceholders = {"case", "tier", "kind",     "data",      "frf", "meta",
                                             "order", "p",  "r",        "domain",    "method", "omega_scale",
                                             "treatment", "out", "fdsid_args", "suite"};

// The placeholders of a command template; an unknown one is bad input.
void check_template(const std::string& option, const std::string& t) {
  for (std::size_t at = t.find('{'); at != std::string::npos; at = t.find('{', at + 1)) {
    const std::size_t end = t.find('}', at);
    if (end == std::string::npos) break;
    const std::string name = t.substr(at + 1, end - at - 1);
    // Only {identifier} is a placeholder: a shell's {"..."} or ${VAR} is left alone.
    const bool identifier = !name.empty() && name.find_first_not_of("abcdefghijklmnopqrstuvwxyz_") == std::string::npos;
    if (identifier && at > 0 && t[at - 1] == '$') continue;
    if (identifier && !kPlaceholders.count(name))
      throw Error(ErrorKind::Input, option,
                  "unknown placeholder {" + name + "}; use {data} {frf} {meta} {order} {p} {r} {domain} {method} "
                  "{omega_scale} {treatment} {kind} {case} {tier} {out} {fdsid_args} {suite}");
  }
}

std::string substitute(std::string t, const std::map<std::string, std::string>& values) {
  for (const auto& [name, value] : values) {
    const std::string key = "{" + name + "}";
    for (std::size_t at = t.find(key); at != std::string::npos; at = t.find(key, at + value.size()))
      t.replace(at, key.size(), value);
  }
  return t;
}

// Paths go into a shell command unquoted: only characters that need no quoting.
void require_plain_path(const std::string& path, const std::string& what) {
  for (char ch : path)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || std::string("._/-+:=@%,").find(ch) != std::string::npos))
      throw Error(ErrorKind::Input, what, "\"" + path + "\" contains a character a shell would need quoted; use a path "
                                          "without spaces or quotes");
}

struct Outcome {
  bool timed_out = false;
  int exit_status = -1, signal = 0;
  double seconds = 0;
};

// Runs `command` with /bin/sh in its own process group, stdout and stderr to
// files, killing the group after `timeout` seconds.
Outcome run_command(const std::string& command, const std::string& stdout_path, const std::string& stderr_path,
                    double timeout) {
  Outcome o;
  const auto t0 = std::chrono::steady_clock::now();
  std::cout.flush();
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) throw Error(ErrorKind::Input, "conformance", "cannot start the candidate (fork failed)");
  if (pid == 0) {
    setpgid(0, 0);
    const int in = open("/dev/null", O_RDONLY);
    const int out = open(stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in >= 0) dup2(in, 0);
    if (out >= 0) dup2(out, 1);
    if (err >= 0) dup2(err, 2);
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  setpgid(pid, pid);
  int status = 0;
  for (;;) {
    const pid_t w = waitpid(pid, &status, WNOHANG);
    o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (w == pid) break;
    if (o.seconds > timeout) {
      o.timed_out = true;
      kill(-pid, SIGKILL);
      waitpid(pid, &status, 0);
      return o;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(o.seconds < 1 ? 2 : 20));
  }
  kill(-pid, SIGKILL);  // what the candidate left running in its group
  if (WIFEXITED(status)) o.exit_status = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) o.signal = WTERMSIG(status);
  return o;
}

// The last lines of the candidate's stderr (at most 400 characters).
std::string excerpt(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  std::string s = ss.str();
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  if (s.size() > 400) s = "..." + s.substr(s.size() - 400);
  return s;
}

struct CaseRun {
  const CertifiedCase* c = nullptr;
  std::string command;
  Outcome outcome;
  CaseScore score;
  std::string failure;  ///< why no model could be scored (empty: scored)
  std::string stderr_excerpt;
  bool pass() const { return failure.empty() && score.pass; }
  std::string verdict() const { return failure.empty() ? score.verdict : failure; }
};

CaseRun run_case(const CertifiedCase& c, const std::string& command_template, const std::string& suite,
                 const std::string& work, double timeout) {
  CaseRun run;
  run.c = &c;
  const CaseSpec& s = c.spec;
  const std::string dir = suite + "/";
  const std::string out = work + "/" + s.name + ".json";
  std::error_code ec;
  fs::remove(out, ec);
  run.command = substitute(
      command_template,
      {{"case", s.name}, {"tier", s.tier}, {"kind", to_string(s.kind)}, {"data", s.data.empty() ? "" : dir + s.data},
       {"frf", s.frf.empty() ? "" : dir + s.frf}, {"meta", s.meta.empty() ? "" : dir + s.meta},
       {"order", std::to_string(s.order)}, {"p", s.p ? std::to_string(s.p) : ""}, {"r", std::to_string(s.r)},
       {"domain", to_string(s.domain)},
       {"method", s.kind == CaseKind::Spectrum ? to_string(s.spectrum_method)
                  : s.domain == Domain::Continuous ? to_string(s.continuous_method)
                                                   : "discrete"},
       {"omega_scale", s.omega_scale > 0 ? fmt(s.omega_scale, 17) : ""},
       {"treatment", name_of(case_treatment_names(), s.treatment)}, {"out", out},
       {"fdsid_args", s.fdsid_arguments(suite)}, {"suite", suite}});
  const std::string err_path = work + "/" + s.name + ".stderr";
  run.outcome = run_command(run.command, work + "/" + s.name + ".stdout", err_path, timeout);
  run.stderr_excerpt = excerpt(err_path);
  const Outcome& o = run.outcome;
  if (o.timed_out) run.failure = "the candidate ran past --timeout " + fmt(timeout, 3) + " s and was killed";
  else if (o.signal) run.failure = "the candidate was killed by signal " + std::to_string(o.signal);
  else if (o.exit_status != 0) run.failure = "the candidate exited " + std::to_string(o.exit_status);
  if (!run.failure.empty()) return run;
  std::ifstream f(out);
  if (!f) {
    run.failure = "the candidate wrote no model JSON to {out}";
    return run;
  }
  try {
    const json j = json::parse(f);
    const StateSpace model = model_from_json(j, "candidate model");
    run.score = score_candidate(c, model);
  } catch (const json::parse_error& e) {
    run.failure = std::string("the candidate's output is not JSON (") + e.what() + ")";
  } catch (const Error& e) {
    run.failure = std::string("the candidate's output is not a model: ") + e.what();
  }
  return run;
}

std::string xml_escape(const std::string& s) {
  std::string o;
  for (char ch : s) {
    switch (ch) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default:
        if (static_cast<unsigned char>(ch) < 0x20 && ch != '\n' && ch != '\t') o += ' ';
        else o += ch;
    }
  }
  return o;
}

std::string junit(const std::vector<CaseRun>& runs, double seconds) {
  int failures = 0;
  for (const auto& r : runs) failures += !r.pass();
  std::string x = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n";
  x += "  <testsuite name=\"fdsid-conformance\" tests=\"" + std::to_string(runs.size()) + "\" failures=\"" +
       std::to_string(failures) + "\" errors=\"0\" time=\"" + fmt(seconds, 6) + "\">\n";
  for (const auto& r : runs) {
    x += "    <testcase classname=\"fdsid.certified." + r.c->spec.tier + "\" name=\"" + xml_escape(r.c->spec.name) +
         "\" time=\"" + fmt(r.outcome.seconds, 6) + "\">\n";
    if (!r.pass())
      x += "      <failure message=\"" + xml_escape(r.verdict()) + "\">" + xml_escape(r.command) + "</failure>\n";
    if (!r.stderr_excerpt.empty()) x += "      <system-err>" + xml_escape(r.stderr_excerpt) + "</system-err>\n";
    x += "    </testcase>\n";
  }
  return x + "  </testsuite>\n</testsuites>\n";
}

json report_json(const std::vector<CaseRun>& runs, const ConformanceCommand& c) {
  json cases = json::array();
  int passed = 0;
  for (const auto& r : runs) {
    passed += r.pass();
    json q = json::array();
    for (const auto& s : r.score.quantities)
      q.push_back({{"name", s.name}, {"lre", s.lre}, {"certified_digits", s.certified_digits}});
    json j = {{"case", r.c->spec.name},   {"tier", r.c->spec.tier},     {"kind", to_string(r.c->spec.kind)},
              {"pass", r.pass()},         {"verdict", r.verdict()},     {"command", r.command},
              {"seconds", r.outcome.seconds}, {"timed_out", r.outcome.timed_out},
              {"exit_status", r.outcome.exit_status}, {"signal", r.outcome.signal}, {"lre", q}};
    if (!r.stderr_excerpt.empty()) j["stderr"] = r.stderr_excerpt;
    if (!r.score.comparison.is_null()) j["comparison"] = r.score.comparison;
    cases.push_back(j);
  }
  return {{"suite", c.suite}, {"total", runs.size()}, {"passed", passed}, {"failed", int(runs.size()) - passed},
          {"all_pass", passed == int(runs.size())}, {"cases", cases}};
}

int run(const ConformanceCommand& c) {
  const std::string& generic = c.candidate;
  if (generic.empty() && (c.candidate_spectrum.empty() || c.candidate_frf.empty()))
    throw Error(ErrorKind::Input, "--candidate",
                "give the command that identifies one case, e.g. --candidate 'python3 mine.py {data} {order} {out}' "
                "(or both --candidate-spectrum and --candidate-frf)");
  check_template("--candidate", generic);
  check_template("--candidate-spectrum", c.candidate_spectrum);
  check_template("--candidate-frf", c.candidate_frf);
  if (!(c.timeout > 0)) throw Error(ErrorKind::Input, "--timeout", "must be a positive number of seconds");
  require_plain_path(c.suite, "--suite");
  if (!c.junit_path.empty()) refuse_overwrite(c.junit_path, {}, "--junit");
  // Everything read before any candidate runs: a bad suite is bad input.
  std::vector<CaseSpec> specs = read_suite_manifest(c.suite);
  for (const std::string& t : c.tiers)
    if (t != "lower" && t != "average" && t != "higher")
      throw Error(ErrorKind::Input, "--tier", "\"" + t + "\" is not lower, average or higher");
  for (const std::string& name : c.cases) {
    bool found = false;
    for (const auto& s : specs) found = found || s.name == name;
    if (!found) throw Error(ErrorKind::Input, "--case", "\"" + name + "\" is not in " + c.suite + "/cases.json");
  }
  std::vector<CertifiedCase> cases;
  for (const CaseSpec& s : specs) {
    if (!c.tiers.empty() && std::find(c.tiers.begin(), c.tiers.end(), s.tier) == c.tiers.end()) continue;
    if (!c.cases.empty() && std::find(c.cases.begin(), c.cases.end(), s.name) == c.cases.end()) continue;
    cases.push_back(read_certified_case(c.suite, s));
  }
  if (cases.empty()) throw Error(ErrorKind::Input, "--tier/--case", "select no case of " + c.suite);

  std::string work = c.work;
  bool temporary = false;
  if (work.empty()) {
    char pattern[] = "/tmp/fdsid-conformance-XXXXXX";
    if (!mkdtemp(pattern)) throw Error(ErrorKind::Input, "conformance", "cannot create a folder under /tmp");
    work = pattern;
    temporary = true;
  } else {
    std::error_code ec;
    fs::create_directories(work, ec);
    if (ec || !fs::is_directory(work)) throw Error(ErrorKind::Input, "--work", "cannot create folder " + work);
    require_plain_path(work, "--work");
  }

  const bool to_stdout = c.json_path == "-";
  std::ostream& table = to_stdout ? std::cerr : std::cout;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<CaseRun> runs;
  char line[512];
  std::snprintf(line, sizeof line, "%-40s %-8s %-5s %7s  %s\n", "case", "tier", "", "seconds",
                "LRE (log relative error) / certified digits");
  table << line;
  for (const CertifiedCase& k : cases) {
    const std::string& t = k.spec.kind == CaseKind::Spectrum ? (c.candidate_spectrum.empty() ? generic : c.candidate_spectrum)
                                                              : (c.candidate_frf.empty() ? generic : c.candidate_frf);
    runs.push_back(run_case(k, t, c.suite, work, c.timeout));
    const CaseRun& r = runs.back();
    std::string scores;
    for (const auto& q : r.score.quantities) scores += q.name + " " + fmt(q.lre, 3) + "/" + std::to_string(q.certified_digits) + "  ";
    std::snprintf(line, sizeof line, "%-40s %-8s %-5s %7.2f  %s\n", k.spec.name.c_str(), k.spec.tier.c_str(),
                  r.pass() ? "PASS" : "FAIL", r.outcome.seconds, scores.c_str());
    table << line;
    if (!r.pass()) {
      table << "    " << r.verdict() << "\n";
      if (!r.failure.empty() && !r.stderr_excerpt.empty()) table << "    stderr: " << r.stderr_excerpt << "\n";
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  int passed = 0;
  for (const auto& r : runs) passed += r.pass();
  table << passed << " of " << runs.size() << " certified cases pass (" << fmt(seconds, 3) << " s)"
        << (temporary ? "" : "; the candidate's outputs are in " + work) << "\n";
  if (!c.json_path.empty()) emit_json(c.json_path, report_json(runs, c));
  if (!c.junit_path.empty()) write_text_file(c.junit_path, junit(runs, seconds));
  if (temporary) {
    std::error_code ec;
    fs::remove_all(work, ec);
  }
  return passed == int(runs.size()) ? 0 : 1;
}

}  // namespace

void register_conformance(CLI::App& app, Action& chosen) {
  auto c = std::make_shared<ConformanceCommand>();
  auto* sub = app.add_subcommand(
      "conformance", "run another implementation over the certified suite and score its models (exit 1: a case fails)");
  sub->add_option("--candidate", c->candidate,
                  "command run per case, with placeholders {data} {frf} {meta} {order} {p} {r} {domain} {method} "
                  "{omega_scale} {treatment} {kind} {case} {tier} {out} {fdsid_args}; it writes a model JSON to {out}");
  sub->add_option("--candidate-spectrum", c->candidate_spectrum, "command for the spectrum cases (instead of --candidate)");
  sub->add_option("--candidate-frf", c->candidate_frf, "command for the FRF and records cases (instead of --candidate)");
  sub->add_option("--suite", c->suite, "the certified suite (default fixtures/certified)")->check(CLI::ExistingDirectory);
  sub->add_option("--tier", c->tiers, "only these tiers (lower, average, higher)");
  sub->add_option("--case", c->cases, "only these cases");
  sub->add_option("--timeout", c->timeout, "seconds per case before the candidate is killed (default 120)");
  add_json_option(sub, c->json_path, "write the scores here (- = stdout)");
  sub->add_option("--junit", c->junit_path, "write JUnit XML here (GitLab, GitHub, Jenkins test reports)")
      ->check(output_path("--junit"));
  sub->add_option("--work", c->work, "keep the candidate's outputs and stderr in this folder (default: a temporary one)");
  on_parsed(sub, c, chosen, run);
}

}  // namespace fdsid::cli
