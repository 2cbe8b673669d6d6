// Names and JSON encodings of the dataset format (docs/format.md), shared by its writer
// (preprocess/preprocess.cpp) and its reader (dataset/dataset.cpp) alone.
#pragma once

#include "dataset/dataset.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace raypc::dataset::format {

inline constexpr const char* kManifest = "dataset.json";
inline constexpr const char* kFormatName = "raypc-dataset";
inline constexpr int kVersion = 2;               // 2: the manifest names the arrays' `encoding`
inline constexpr int kOldestReadableVersion = 1;  // 1: float32 arrays
inline constexpr const char* kSampleCoords = "sample_coords.f32";
// The sample's grid-point indices (uint32, canonical order), from which a computed variable's sample
// column is made: present where the manifest has computed variables.
inline constexpr const char* kSampleCells = "sample_cells.u32";
inline constexpr const char* kStepManifest = "step.json";
inline constexpr const char* kStepSample = "sample.f32";
// The size and modification time of every file a step was made from, so that a resumed run redoes
// a finished step whose input changed since (preprocess.cpp); the reader does not use it.
inline constexpr const char* kStepInputs = "inputs.json";
inline constexpr const char* kLockFile = ".lock";  // DatasetWriteLock

std::filesystem::path stepDir(const std::filesystem::path& dataset, int step);
std::filesystem::path levelDir(const std::filesystem::path& stepDir, int level);
std::filesystem::path valuesFile(const std::filesystem::path& levelDir, const std::string& stem);
std::filesystem::path encodedValuesFile(const std::filesystem::path& levelDir, const std::string& stem);  // u16
std::filesystem::path boundsFile(const std::filesystem::path& levelDir, const std::string& stem);

nlohmann::json toJson(const grid::SphericalGrid& grid);
grid::SphericalGrid gridFromJson(const nlohmann::json& j);
nlohmann::json toJson(const VariableStats& stats);
VariableStats statsFromJson(const nlohmann::json& j);

}  // namespace raypc::dataset::format
