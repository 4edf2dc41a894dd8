#pragma once
/// JSON of every result the command-line tool writes with --json: one
/// serialisation per result type, field names fixed by ../shared/CONTRACTS.md
/// (add fields freely; never rename or drop one). The tool writes
/// to_json(...).dump(2) + "\n".
///
/// The serialisations of the model, the spectral factor, the FRF model, the
/// record meta, the gap report and its validation live beside their types
/// (io.cpp, gap.cpp, gap_validate.cpp); the overloads here name them and add
/// what the tool records about its run (input files, options).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fdsid/gap.hpp"
#include "fdsid/gap_validate.hpp"
#include "fdsid/io.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/workflow.hpp"

namespace fdsid {

/// Model file of the contracts: domain, sample_time, A, B, C, D.
nlohmann::json to_json(const StateSpace& model);

/// `identify-spectrum --json`: result_to_json plus "data" (the CSV it was read from).
nlohmann::json to_json(const SpectrumResult& result, const std::string& data_path);

/// `identify-frf --json`: frf_result_to_json(result, method) plus "source"
/// (files, variance, errors-in-variables or improper treatment) and, for an
/// improper G, "represents": "inverse".
nlohmann::json to_json(const FrfResult& result, const std::string& method, const FrfSource& source);

/// The "source" object of identify-frf.
nlohmann::json to_json(const FrfSource& source);

/// Meta of periodic records: period, periods, sample_time, excited_lines.
nlohmann::json to_json(const RecordMeta& meta);

/// `reproduce table1 --json`: {"source", "rows": [{"M", "sigma4", "sigma5", "vo_sigmas", "akcay_sigmas"}]}.
nlohmann::json to_json(const std::vector<Table1Row>& rows);

/// `reproduce table2 --json`: {"source", "realizations", "seed", "noise", "rows": [{"M", "l2", "linf", …}]}.
nlohmann::json to_json(const std::vector<Table2Row>& rows, const Table2Options& options);

/// `reproduce fig1|fig2 --json`: {"figure", "frequency", "ratio", "bound", …}.
nlohmann::json to_json(const FigureResult& result, int figure, const FigureOptions& options);

/// `gap --json`: gap_report_to_json (CONTRACTS.md).
nlohmann::json to_json(const GapReport& report);

/// `gap-validate --json`: gap_validation_to_json.
nlohmann::json to_json(const GapValidation& validation);

/// `check --json`: agree, orders, p, r, method, extension, the three errors,
/// the tolerances and their rule, and the reference's model.
nlohmann::json to_json(const OracleCheck& check);
/// `fdsid check --frf` / `--data --meta`: agree, quantities (distance, tolerance, ratio), settings, reference model.
nlohmann::json to_json(const FrfOracleCheck& check);
/// The "fit" object of identify-frf's JSON.
nlohmann::json to_json(const FitVerdict& fit);

}  // namespace fdsid
