// Internal to src/preprocess: what the phases of preprocess() share (preprocess.cpp runs them;
// the pathline phase lives in preprocess_pathlines.cpp).
#pragma once

#include "preprocess/preprocess.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace raypc::preprocess::phases {

// A variable of the dataset: stored (as the reader returns it, or derived and stored), or computed
// when read (a shell anomaly: `computed`, after the stored ones).
struct VariableSpec {
    std::string name, units;
    bool derived;
    // What it comes from: a stored variable's name in the input, a derived one's inputs.
    std::string source;
    std::string longName;  // the input's long_name, where it has one
    std::optional<dataset::ShellAnomalyOf> computed = {};
};

// The size and modification time of each of `files` (a step's inputs.json, format::kStepInputs).
// Throws raypc::Error naming a file whose size or time cannot be read.
nlohmann::json filesFingerprint(const std::vector<std::filesystem::path>& files);

// Throws raypc::Error "preprocess: cancelled" once options.cancel is set (between steps and sets).
void throwIfCancelled(const PreprocessOptions& options);

// The pathline settings as the manifest and every set's lines.json store them.
nlohmann::json pathlineSettings(const PathlineOptions& options);

// Throws raypc::Error naming the option when the pathline options do not fit the variables.
void checkPathlineOptions(const PathlineOptions& options, const std::vector<VariableSpec>& specs);

// The pathline phase: critical points and pathlines of every step, each step's set written
// atomically and skipped on a rerun when it was made with the same settings and reaches the
// same last step. Reads the written level-0 arrays back (computed variables computed from them);
// `specs` are the dataset's variables, stored then computed; `stepJsons` are the steps' manifests.
void writePathlines(const std::filesystem::path& outDir, const grid::SphericalGrid& grid,
                    const std::vector<VariableSpec>& specs, const std::vector<nlohmann::json>& stepJsons,
                    const PreprocessOptions& options, PreprocessSummary& summary);

}  // namespace raypc::preprocess::phases
