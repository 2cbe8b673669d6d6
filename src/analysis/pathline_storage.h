// The stored form of pathline sets in a dataset directory (docs/format.md, "Pathlines").
//
// Thread safety: free functions; concurrent reads are safe, writes go to a directory the caller
// renames into place.
#pragma once

#include "analysis/pathlines.h"

#include <filesystem>
#include <string>
#include <vector>

namespace raypc::analysis {

// The version of lines.json this build writes: 2 added the "seed persistence" column; version 1
// sets (without it) are still read.
inline constexpr int kPathlineSetVersion = 2;

// DATASET/pathlines/NNNN.
std::filesystem::path pathlineDir(const std::filesystem::path& dataset, int step);

// Writes `set` into `dir` (created; the caller writes into a temporary directory and renames it).
// Throws raypc::Error on I/O failure.
void writePathlineSet(const std::filesystem::path& dir, const PathlineSet& set);

// Reads the set of lines injected at `step` from the dataset directory `dataset`. Throws
// raypc::Error naming the file when it is missing (e.g. preprocessed with --no-pathlines), of the
// wrong size or malformed.
PathlineSet loadPathlineSet(const std::filesystem::path& dataset, int step);
// Why a dataset has no pathlines, as its manifest says (`no_pathlines`: the model has no velocity,
// its flow has missing values, preprocessed with --no-pathlines), or a general reason for a dataset
// written before it was said.
std::string noPathlinesReason(const std::filesystem::path& dataset);

// The longest window of injection steps shown at once (the state's pathlines.window, the server's
// /api/pathlines, Python's Dataset.pathlines).
inline constexpr int kMaxPathlineWindow = 1000;
// Throws raypc::Error "<what>: 0 out of range 1..1000" unless 1 <= window <= kMaxPathlineWindow.
void checkPathlineWindow(int window, const std::string& what = "window");

// What a renderer shows at step s (paper: "all pathlines spawned during the last 10 time steps"):
// the sets injected at steps max(0, s - window + 1) .. s, oldest first. Throws like loadPathlineSet,
// and like checkPathlineWindow.
std::vector<PathlineSet> loadPathlineWindow(const std::filesystem::path& dataset, int step, int window = 10);

}  // namespace raypc::analysis
