// fdsid command-line tool: each subcommand registers itself (one file per
// subcommand or family in cli/); this file parses and dispatches. Every number
// comes from the fast/ library (and the reference, for --precision high and check).
#include <exception>
#include <iostream>

#include "common.hpp"
#include "fdsid/error.hpp"

#ifndef FDSID_VERSION
#define FDSID_VERSION "unknown"
#endif

int main(int argc, char** argv) {
  using namespace fdsid::cli;
  CLI::App app{"fdsid: frequency-domain subspace identification (Akcay 2011, Pintelon 2002)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "fdsid " FDSID_VERSION);
  Action chosen;
  register_reproduce(app, chosen);
  register_identify_frf(app, chosen);
  register_simulate_records(app, chosen);
  register_identify_spectrum(app, chosen);
  register_check(app, chosen);
  register_conformance(app, chosen);
  register_certify(app, chosen);
  register_sample_spectrum(app, chosen);
  register_gap(app, chosen);
  register_records(app, chosen);

  if (unknown_subcommand(app, argc, argv)) return 2;
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ExtrasError& e) {
    // CLI11 says "The following arguments were not expected: 3 --realisations"
    // (reversed, no hint): name the unknown option and the nearest known one.
    std::cerr << "fdsid: " << unexpected_arguments(app, argc, argv, e.what()) << "\n";
    return 2;
  } catch (const CLI::ParseError& e) {
    std::cerr << "fdsid: " << e.what() << "\n";
    return 2;
  }
  try {
    return chosen ? chosen() : 2;
  } catch (const fdsid::Error& e) {
    std::cerr << "fdsid: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "fdsid: internal error: " << e.what() << "\n";
    return 2;
  }
}
