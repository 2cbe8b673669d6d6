// A preprocessed RayPC dataset: what the renderer, the server and the CLI load.
// The on-disk format is documented in docs/format.md; arrays are memory-mapped raw
// little-endian float32 in canonical grid order (grid.h), so a step loads without parsing.
//
// Variables: the stored ones of the input (contest names and units) plus derived ones
// ("radial velocity" and "velocity magnitude" in cm/yr). Coordinates (x, y, z in km,
// lat/lon in degrees, radius and depth in km) are not stored: they are functions of the grid.
//
// Thread safety: a Dataset and the StepVolumes it returns are immutable and may be shared.
#pragma once

#include "core/mapped_file.h"
#include "data/coordinates.h"
#include "data/grid.h"
#include "data/snapshot.h"

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace raypc {

inline constexpr int kHistogramBins = 256;
inline constexpr int kLevelCount = 3;  // level 0 = full resolution, 1 and 2 coarser (1/8 each)

struct ValueRange {
    float min = 0, max = 0;
};

// Per-variable statistics, volume-weighted (each grid point counts with its dual-cell volume).
struct VariableStats {
    ValueRange range;  // exact min and max over the grid points
    double mean = 0;   // volume-weighted mean
    std::vector<double> histogram;  // kHistogramBins volume fractions over `range`; sums to 1
};

struct VariableInfo {
    std::string name;   // e.g. "temperature anomaly", "radial velocity"
    std::string units;  // e.g. "K", "cm/yr"
    bool derived = false;
    std::string fileStem;  // file-safe name of its arrays
    VariableStats global;  // over all steps (histogram rebinned from the steps' histograms)
};

struct StepInfo {
    int index = 0;
    double timeMyr = 0;
    std::string source;  // input file name
    std::vector<VariableStats> stats;  // one per variable, same order as Dataset::variables()
};

struct LevelInfo {
    SphericalGrid grid;
    BrickLayout bricks;
};


// One step at one level of detail: every variable's values plus per-brick bounds.
class StepVolume {
public:
    // Builds a volume in memory from a snapshot (computing brick bounds); used by tests
    // and by preprocessing. Field order becomes variable order.
    static std::shared_ptr<StepVolume> fromSnapshot(const Snapshot& snapshot, uint32_t brickSize = 8);

    const SphericalGrid& grid() const { return m_grid; }
    const BrickLayout& bricks() const { return m_bricks; }
    size_t variableCount() const { return m_values.size(); }
    // grid().cellCount() values of variable `var`, canonical order.
    const float* values(size_t var) const { return m_values[var]; }
    // bricks().brickCount() pairs (min, max) of variable `var`.
    const float* brickBounds(size_t var) const { return m_bounds[var]; }
    // The same over bricks of `brickSize` points (BrickLayout::forGrid(grid(), brickSize)): the stored
    // bounds at bricks().size, otherwise computed from the values on first use and kept with the
    // volume (the renderer skips smaller bricks on coarse levels). Thread-safe.
    const float* brickBounds(size_t var, uint32_t brickSize) const;
    // nodeGradient (data/grid.h) of variable `var`: computed from the values on first use and kept
    // with the volume (the ray caster's shading interpolates it). Thread-safe.
    const NodeGradient& nodeGradient(size_t var) const;

private:
    friend class Dataset;
    SphericalGrid m_grid;
    BrickLayout m_bricks;
    std::vector<const float*> m_values, m_bounds;
    mutable std::mutex m_derivedMutex;
    mutable std::map<std::pair<size_t, uint32_t>, std::vector<float>> m_derivedBounds;
    mutable std::map<size_t, NodeGradient> m_gradients;
    std::vector<MappedFile> m_mapped;              // when loaded from disk
    std::vector<std::vector<float>> m_owned;       // when built in memory
};

// The parallel-coordinates sample of one step: `rows` cells, columns = coordinates
// (coordinateInfos() order) then variables (Dataset::variables() order), row-major.
struct SampleTable {
    std::vector<std::string> columns;
    std::vector<std::string> units;
    size_t rows = 0;
    std::vector<float> values;  // rows * columns.size()
    float at(size_t row, size_t column) const { return values[row * columns.size() + column]; }
};

// Exclusive write access to a dataset directory, so that two `raypc preprocess` runs into one
// directory cannot interleave: flock(2) on DIR/.lock, released when the object is destroyed or
// the process ends (also when it is killed, so a stale lock never blocks a rerun). The file
// holds the holder's pid and host name, for the message to the one refused. Reading a dataset
// takes no lock (Dataset::open refuses an unfinished one).
class DatasetWriteLock {
public:
    // Creates `dir` if needed and locks it. Throws raypc::Error naming the directory and the
    // holder (pid, host) when another process holds the lock, or naming the file on an I/O error.
    explicit DatasetWriteLock(const std::filesystem::path& dir);
    ~DatasetWriteLock();
    DatasetWriteLock(const DatasetWriteLock&) = delete;
    DatasetWriteLock& operator=(const DatasetWriteLock&) = delete;

    // Removes the lock file while still holding the lock (before removing the directory of a
    // run that leaves nothing); a process that opened the old file sees it is gone and retries.
    void removeFile();

private:
    std::filesystem::path m_path;
    int m_fd = -1;
};

class Dataset {
public:
    // Opens a dataset directory. Throws raypc::Error naming the directory if it is not a
    // complete RayPC dataset of a supported format version.
    static std::shared_ptr<const Dataset> open(const std::filesystem::path& dir);

    const std::filesystem::path& dir() const { return m_dir; }
    const std::vector<VariableInfo>& variables() const { return m_variables; }
    // The variables' names, in order (for messages and catalogs).
    std::vector<std::string> variableNames() const;
    // Index of the variable named `name`, or -1.
    int variableIndex(const std::string& name) const;
    const std::vector<StepInfo>& steps() const { return m_steps; }
    const std::vector<LevelInfo>& levels() const { return m_levels; }
    double dtMyr() const { return m_dtMyr; }

    // The range checks of every request that names a step or a level (CLI options, state documents,
    // HTTP parameters): throw raypc::Error "<what>: 300 out of range 0..11" unless valid.
    void checkStep(int step, std::string_view what = "step") const;
    void checkLevel(int level, std::string_view what = "level") const;

    // Maps step `step` at level `level`. Throws raypc::Error if out of range or unreadable.
    std::shared_ptr<const StepVolume> load(int step, int level) const;
    SampleTable loadSample(int step) const;

private:
    std::filesystem::path m_dir;
    std::vector<VariableInfo> m_variables;
    std::vector<StepInfo> m_steps;
    std::vector<LevelInfo> m_levels;
    double m_dtMyr = 2.0;
    size_t m_sampleRows = 0;
};

}  // namespace raypc
