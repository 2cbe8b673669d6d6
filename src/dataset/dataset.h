// A preprocessed RayPC dataset: what the renderer, the server and the CLI load.
// The on-disk format is documented in docs/format.md; arrays are memory-mapped raw
// little-endian float32 in canonical grid order (grid.h), so a step loads without parsing.
//
// Variables: the stored ones of the input (contest names and units) plus derived ones
// ("radial velocity" and "velocity magnitude" in cm/yr, stored), then the shell anomalies
// ("X anomaly", "X anomaly %"; dataset/shell_anomaly.h), computed when read. Coordinates (x, y, z in km,
// lat/lon in degrees, radius and depth in km) are not stored: they are functions of the grid.
//
// Thread safety: a Dataset and the StepVolumes it returns are immutable and may be shared.
#pragma once

#include "core/huge_pages.h"
#include "core/mapped_file.h"
#include "core/spare_blocks.h"
#include "grid/coordinates.h"
#include "grid/grid.h"
#include "grid/snapshot.h"
#include "dataset/shell_anomaly.h"
#include "dataset/value_encoding.h"

#include <array>
#include <atomic>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace raypc::dataset {

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
    // The volume fraction of the data's region where the variable is missing (NaN): left out of the
    // range, mean and histogram; and the grid points where it is missing, those that pad a regional
    // grid to the globe included (level 0). 0 in datasets written before missing values were kept.
    double missingFraction = 0;
    size_t missingPoints = 0;
};

struct VariableInfo {
    std::string name;   // e.g. "temperature anomaly", "radial velocity"
    std::string units;  // e.g. "K", "cm/yr"
    bool derived = false;
    // A stored variable's name in the input files, a derived one's inputs ("vx, vy, vz"); empty in
    // datasets written before it was recorded.
    std::string source;
    std::string longName;  // the input's CF long_name, or empty
    // Whether its arrays are stored; a variable that is not is computed when read (`computed`).
    bool stored = true;
    std::optional<ShellAnomalyOf> computed;
    std::string fileStem;  // file-safe name of its arrays (a stored variable's)
    VariableStats global;  // over all steps (histogram rebinned from the steps' histograms)
};

struct StepInfo {
    int index = 0;
    double timeMyr = 0;
    std::string source;  // input file name
    std::vector<VariableStats> stats;  // one per variable, same order as Dataset::variables()
    // Per variable, the level-0 shell means (grid nR of them, NaN for a shell without a value) of a
    // variable a computed one is made from; empty for the others.
    std::vector<std::vector<double>> shellMeans;
    // Per level, per variable the shell means (the level's nR, NaN for a shell without a value) of a
    // variable a computed one is made from, as StepVolume::shellMeansOf gives them from the level's
    // stored values (for u16 the decoded ones: the same bits); empty for the others, and for every
    // variable in datasets written before they were kept (the volume then computes them).
    std::vector<std::vector<std::vector<double>>> levelShellMeans;
    // How the step was made from a mesh (Snapshot::origin: format, cells, grid points inside a cell,
    // snapped, missing); null for a step read from a netCDF file.
    nlohmann::json origin;
};

struct LevelInfo {
    grid::SphericalGrid grid;
    grid::BrickLayout bricks;
};


// One step at one level of detail: every variable's values plus per-brick bounds.
//
// A dataset of encoding u16 (value_encoding.h) decodes a variable's values on first use of
// values(var) (in parallel) and keeps them with the volume; float32 datasets map their values.
// Computed variables (shell anomalies, after the stored ones) are computed on first use of
// values(var) from the level's own values of their base variable and its shell means on this level,
// and kept with the volume likewise; their brick bounds come from the computed values.
class StepVolume {
public:
    // Builds a volume in memory from a snapshot (computing brick bounds); used by tests
    // and by preprocessing. Field order becomes variable order.
    static std::shared_ptr<StepVolume> fromSnapshot(const grid::Snapshot& snapshot, uint32_t brickSize = 8);

    // Maps the arrays of one level directory (docs/format.md): per variable `<stem>.f32` or
    // `<stem>.u16`, and `<stem>.bricks.f32` (the bounds are copied into memory, the values stay
    // mapped). `ranges`: per variable the step's exact range (the manifest's statistics), or empty
    // for any finite value. `missing`: per stored variable whether the step has missing values (NaN;
    // VariableStats::missingPoints > 0), or empty for none. `computed`: the variables after the stored
    // ones, each computed from a stored one (its index < fileStems.size()). `shellMeans`: per stored
    // variable its shell means on this level as shellMeansOf would compute them (StepInfo::levelShellMeans),
    // empty where not known, or empty for none known. Throws raypc::Error naming
    // the file when one is missing, has the wrong size, or holds brick bounds that are not finite with
    // min <= max within the range (a variable with missing values: or (+inf, -inf)).
    static std::shared_ptr<StepVolume> open(const std::filesystem::path& levelDir, const LevelInfo& level,
                                            const std::vector<std::string>& fileStems, ValueEncoding encoding,
                                            std::span<const ValueRange> ranges = {}, std::span<const char> missing = {},
                                            std::span<const ShellAnomalyOf> computed = {},
                                            std::span<const std::vector<double>> shellMeans = {});

    // A volume of `base`'s variables and one more, the last: `values` (grid().cellCount() of them,
    // canonical order; brick bounds computed here). The base's variables are read through it as the
    // base gives them (decoded on first use), and the base lives as long as this volume. For a
    // field that exists only for one picture (the features painted by id, render/feature_paint.h).
    // Throws raypc::Error when `values` has the wrong size.
    static std::shared_ptr<StepVolume> withVariable(std::shared_ptr<const StepVolume> base, std::vector<float> values);

    const grid::SphericalGrid& grid() const { return m_grid; }
    const grid::BrickLayout& bricks() const { return m_bricks; }
    size_t variableCount() const { return m_values.size(); }
    // Whether variable `var` is computed when read (a shell anomaly), and from what.
    const ShellAnomalyOf* computedFrom(size_t var) const;
    ValueEncoding encoding() const { return m_encoding; }
    // grid().cellCount() values of variable `var`, canonical order. Thread-safe; the first call for a
    // variable of a u16 volume decodes it (its cost: bench/value_encoding_bench.cpp; other threads
    // asking for it meanwhile wait), of a mapped float32
    // volume reads it once to check every value lies within the step's range; later calls are one
    // atomic load. The first call throws raypc::Error naming the file if it was cut short since it
    // was mapped, or (float32) for the first value outside the range (NaN, Inf, 3.4e38), with its
    // position.
    const float* values(size_t var) const
    {
        const float* p = m_values[var].load(std::memory_order_acquire);
        return p ? p : decode(var);
    }
    // values(var)[grid().index(iLat, iR, iLon)], without decoding the whole variable when it is not
    // decoded yet (for a few samples, such as the pathlines' attributes): a computed variable from its
    // base's value and the mean of the point's shell (the step's shell means computed once from a
    // decoded copy of the base that is not kept: the same bits). Thread-safe. Throws as values() does (float32: for this value only).
    float value(size_t var, size_t iLat, size_t iR, size_t iLon) const;
    // value() of every point of the box [begin[a], end[a]) of each axis (lat, r, lon) into `out` (the
    // box's shape, C order), for a box much smaller than the grid (Python's lazy xarray arrays): the
    // file is checked once for the box, not once per value; a shell anomaly not computed yet comes
    // from its base on the box's whole shells (their means), the same bits as values(). Thread-safe;
    // throws as value() does.
    void valuesInBox(size_t var, const std::array<size_t, 3>& begin, const std::array<size_t, 3>& end, float* out) const;
    // One variable's values read point by point, without decoding or computing the whole variable:
    // the decoded array when there is one, otherwise a u16 variable's points decoded one by one
    // (Uint16PointDecoder, its tables built once per volume) and a shell anomaly's from its base's
    // values and shell means (shellMeansOf: no array of the anomaly, no brick bounds of it); its base
    // read point by point too when the means are known without decoding it (kept in the manifest:
    // StepInfo::levelShellMeans), else decoded whole (the means need every point).
    // The same bits as values(var). For passes that read a few points of many variables (a
    // selection's features: extractFeatures); a pass over every point should use values().
    class PointValues {
    public:
        float at(size_t index, size_t iLat, size_t iR, size_t iLon) const
        {
            const float x =
                m_values ? m_values[index] : m_decoder->decode(m_encoded, m_bounds, index, iLat, iR, iLon, m_missing);
            return m_means ? shellAnomalyValue(x, m_means[iR], m_kind) : x;
        }

    private:
        friend class StepVolume;
        // The variable's values, or a shell anomaly's base's: decoded, mapped float32 or computed; else
        // a u16 one's encoded points.
        const float* m_values = nullptr;
        const Uint16PointDecoder* m_decoder = nullptr;
        const uint16_t* m_encoded = nullptr;
        const float* m_bounds = nullptr;
        bool m_missing = false;
        const double* m_means = nullptr;  // a shell anomaly not computed: its base's shell means
        ShellAnomalyKind m_kind = ShellAnomalyKind::Difference;
    };
    // Thread-safe; the reader lives as long as the volume. Throws as values() does (a file cut short,
    // a float32 value outside the range).
    PointValues pointValues(size_t var) const;
    // Whether pointValues(var) reads an array (decoded, mapped float32) rather than decoding points.
    bool pointValuesDirect(size_t var) const;
    // The shell means (grid().nR() of them) of variable `var` on this level, as a shell anomaly of it
    // is computed with (shellMeans of values(var), the same bits): computed on first use and kept.
    // A u16 variable not decoded yet is decoded into a copy dropped at once, so that a few point
    // reads keep no array of the grid. Thread-safe.
    const std::vector<double>& shellMeansOf(size_t var) const;
    // Whether shellMeansOf(var) is at hand without decoding var: computed already, kept in the
    // manifest, or var's values ready. Thread-safe.
    bool shellMeansReady(size_t var) const;
    // Whether values(var) is ready without decoding.
    bool valuesReady(size_t var) const { return m_values[var].load(std::memory_order_acquire) != nullptr; }
    // bricks().brickCount() pairs (min, max) of variable `var`. Thread-safe; a computed variable's
    // are computed with its values (values(var)).
    const float* brickBounds(size_t var) const;
    // The same over bricks of `brickSize` points (BrickLayout::forGrid(grid(), brickSize)): the stored
    // bounds at bricks().size, otherwise computed from the values on first use and kept with the
    // volume (the renderer skips smaller bricks on coarse levels). Thread-safe.
    const float* brickBounds(size_t var, uint32_t brickSize) const;
    // nodeGradient (grid/grid.h) of variable `var`: computed from the values on first use and kept
    // with the volume (the ray caster's shading interpolates it). Thread-safe.
    const grid::NodeGradient& nodeGradient(size_t var) const;
    // Drops the shading gradients computed so far, their memory given back (core/spare_blocks.h: the
    // next step's gradient takes it already faulted in); returns their bytes. A later nodeGradient
    // computes it again. Only for a volume no one else holds: a renderer keeps pointers into its
    // gradient. Thread-safe.
    size_t dropGradients() const;

    // The largest error of value (iLat, iR, iLon) of variable `var` against the exact value: 0 for
    // float32, for u16 uint16ErrorBound of the brick that owns the point (value_encoding.h; without
    // the half ulp of float32 rounding). A computed variable's: to first order, from its base's bound
    // at the point and the largest on the point's shell (which bounds the error of the shell mean).
    double errorBound(size_t var, size_t iLat, size_t iR, size_t iLon) const;

    // Bytes of the values and bounds the volume holds now: mapped files (page cache), arrays built in
    // memory, and the values of u16 variables decoded so far. Thread-safe.
    size_t memoryBytes() const;
    // Bytes of decoded values held in memory (u16 volumes; 0 for mapped float32). Thread-safe.
    size_t decodedBytes() const { return m_decodedBytes.load(std::memory_order_relaxed); }
    // Reads one value per page of every mapped file, so that a later pass does not wait for the disk.
    // Throws raypc::Error naming a file cut short since it was mapped.
    void touchPages() const;
    // Asks the kernel to read every mapped file in the background (MappedFile::adviseWillNeed): for
    // a reader of points all over the volume (a step's features read every variable at the selected
    // points), whose page faults would otherwise each wait for a small read. Never throws.
    void adviseWillNeed() const noexcept;
    // Drops the mapped files' pages from the process's resident memory (MappedFile::dropResidentPages),
    // for a holder that reads a few points now and then (preprocessing's pathline window). Values
    // read later map them again from the page cache. Never throws.
    void dropResidentPages() const noexcept;
    // Whether a mapped file is shorter now than when it was mapped (MappedFile::cutShort): reading it
    // would raise SIGBUS. The server's step cache asks before it hands out a cached volume.
    bool filesCutShort() const noexcept;

private:
    const float* decode(size_t var) const;
    float mappedValue(size_t var, size_t iLat, size_t iR, size_t iLon) const;  // value() of a stored, undecoded one
    bool hasMissing(size_t var) const { return var < m_missing.size() && m_missing[var]; }
    const float* compute(size_t var) const;
    double shellErrorBound(size_t var, size_t iR) const;
    [[noreturn]] void failValue(size_t var, size_t index, float value) const;

    grid::SphericalGrid m_grid;
    grid::BrickLayout m_bricks;
    ValueEncoding m_encoding = ValueEncoding::Float32;
    std::unique_ptr<std::atomic<const float*>[]> m_valuesStorage;
    std::span<std::atomic<const float*>> m_values;
    std::vector<const float*> m_bounds;
    std::vector<const void*> m_valueFiles;  // per variable its mapped values (u16 or float32), read by decode()
    std::vector<ValueRange> m_ranges;       // per variable the step's range (open)
    std::vector<char> m_missing;            // per variable whether the step has missing values (open)
    mutable std::mutex m_decodeMutex;
    mutable std::vector<SpareArray<float>> m_decoded;  // written whole once, read often (core/spare_blocks.h)
    mutable std::atomic<size_t> m_decodedBytes{0};
    mutable std::mutex m_derivedMutex;
    mutable std::map<std::pair<size_t, uint32_t>, std::vector<float>> m_derivedBounds;
    mutable std::map<size_t, grid::NodeGradient> m_gradients;
    std::optional<Uint16PointDecoder> m_pointDecoder;  // u16 volumes: PointValues' decoding
    std::vector<MappedFile> m_mapped;              // when loaded from disk: per variable its values
    std::vector<std::vector<float>> m_owned;       // when built in memory
    std::shared_ptr<const StepVolume> m_base;      // withVariable: the volume whose variables come first
    size_t m_storedCount = 0;                      // variables before the computed ones
    std::vector<ShellAnomalyOf> m_computed;        // the computed variables, after the stored ones
    mutable std::mutex m_computeMutex;
    mutable std::vector<std::vector<float>> m_computedBounds;    // per computed variable, with its values
    mutable std::map<size_t, std::vector<double>> m_shellMeans;  // per base variable, this level's
};

// One variable of a step read point by point (StepVolume::PointValues) brick by brick: the first read
// of a point decodes every point of the brick that owns it (BrickLayout::index(i / size, …)) into a
// table kept here, so that reads that return to a neighbourhood (a sampler's corners: linking
// features) decode each point once and whatever is never near a read is never decoded. A variable
// whose values are at hand (decoded, mapped float32) is read from them. The same bits as
// PointValues. Not thread-safe: one per thread. Lives no longer than the volume.
class BrickCachedValues {
public:
    BrickCachedValues(const StepVolume& volume, size_t var);
    float at(size_t iLat, size_t iR, size_t iLon)
    {
        if (m_direct)
            return m_points.at(m_grid->index(iLat, iR, iLon), iLat, iR, iLon);
        const size_t brick = m_brickOf[0][iLat] + m_brickOf[1][iR] + m_brickOf[2][iLon];
        if (m_slot[brick] < 0)
            fill(brick);
        return m_decoded[size_t(m_slot[brick]) * m_brickPoints + m_offsetOf[0][iLat] + m_offsetOf[1][iR] +
                         m_offsetOf[2][iLon]];
    }

private:
    void fill(size_t brick);
    const grid::SphericalGrid* m_grid;
    grid::BrickLayout m_bricks;
    StepVolume::PointValues m_points;
    bool m_direct = false;
    // Per axis and index: its part of the owning brick's index and of the point's place in the brick
    // (no division per read).
    std::array<std::vector<uint32_t>, 3> m_brickOf, m_offsetOf;
    size_t m_brickPoints = 0;
    std::vector<int32_t> m_slot;  // per brick its place in m_decoded, or -1
    std::vector<float> m_decoded;  // size³ values per brick decoded
};

// The parallel-coordinates sample of one step: `rows` cells, columns = coordinates
// (coordinateInfos() order) then variables (Dataset::variables() order), row-major. The rows are
// the same cells in every step, so the coordinates are the same too: SampleColumns::Variables
// leaves them out (what a step changes).
enum class SampleColumns { All, Variables };
struct SampleTable {
    std::vector<std::string> columns;
    std::vector<std::string> units;
    size_t rows = 0;
    std::vector<float> values;  // rows * columns.size()
    float at(size_t row, size_t column) const { return values[row * columns.size() + column]; }
};

// The shell means of level `level` that a step's manifest entry `step` keeps ("level_shell_means",
// docs/format.md) for each variable a computed one of `variables` is made from (NaN for a shell
// without a value), empty for the others; all empty when the entry keeps none (a step written before
// they were kept). Checked as Dataset::open checks them: throws raypc::Error "<what>: <field>: ...".
std::vector<std::vector<double>> readLevelShellMeans(const nlohmann::json& step, const std::string& what,
                                                     const std::vector<VariableInfo>& variables, size_t level,
                                                     size_t levelCount, size_t shells);

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
    // complete RayPC dataset of a supported format version; raypc::NotFoundError (core/error_kinds.h)
    // when nothing is at `dir` or it holds no manifest.
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
    // How the level arrays are stored: float32 (format version 1, or `--encoding float32`) or u16.
    ValueEncoding encoding() const { return m_encoding; }

    // The range checks of every request that names a step or a level (CLI options, state documents,
    // HTTP parameters): throw raypc::OutOfRangeError (core/error_kinds.h) "<what>: 300 out of range
    // 0..11" unless valid.
    void checkStep(int step, std::string_view what = "step") const;
    void checkLevel(int level, std::string_view what = "level") const;

    // Maps step `step` at level `level` (StepVolume::open). Throws raypc::Error if out of range or
    // unreadable.
    std::shared_ptr<const StepVolume> load(int step, int level) const;
    SampleTable loadSample(int step, SampleColumns which = SampleColumns::All) const;

private:
    std::filesystem::path m_dir;
    std::vector<VariableInfo> m_variables;
    std::vector<StepInfo> m_steps;
    std::vector<LevelInfo> m_levels;
    double m_dtMyr = 2.0;
    size_t m_sampleRows = 0;
    ValueEncoding m_encoding = ValueEncoding::Float32;
};

}  // namespace raypc::dataset
