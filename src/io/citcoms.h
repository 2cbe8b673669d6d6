// CitcomS output (geodynamics/citcoms): a full sphere is 12 caps (a regional model one), each a
// structured block of nx × ny × nz nodes at (colatitude, longitude, radius), nondimensional: radius
// 1 at the surface (0.55 at the core), velocity in units of κ/R, time in R²/κ, temperature 0 … 1.
// Read in its two forms:
//
// - the combined cap files of its post-processing (visual/batchcombine.py, combine.py, h5tocap):
//   `MODEL.capNN.STEP`, a header line "nx x ny x nz", then one ASCII row per node — colatitude,
//   longitude (radians), radius, the velocity's colatitude, longitude and radial components,
//   temperature, viscosity — the rows in CitcomS' order (y outermost, then x, z fastest). A step
//   is named by any of its cap files (or its OpenDX `.general` header); its caps are found beside it.
// - its HDF5 output (lib/Output_h5.c): `MODEL.h5` with `/coord[cap, nx, ny, nz, 3]` and the
//   attributes of `/input`; `MODEL.STEP.h5` with `/temperature[cap, nx, ny, nz]`,
//   `/velocity[cap, nx, ny, nz, 3]`, `/viscosity`, optionally `/pressure`, and the root attribute
//   `time`. A step is named by its `MODEL.STEP.h5`.
//
// Each cap's cells are hexahedra between neighbouring nodes; they become pieces of a mesh that the
// one mesh resampler (mesh_resample.h) takes onto the spherical grid, as ASPECT's cells do. Read
// with Debian's libhdf5 (C API). Thread safety: HDF5 is built without thread safety on Debian:
// calls are serialised within this file.
#pragma once

#include "io/vtk_xml.h"

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace raypc::io::citcoms {

// What scales CitcomS' nondimensional numbers to the Earth's (docs/format.md, "CitcomS output").
struct Scales {
    double radiusKm = 6371.0;      // R: radius 1 in km
    double diffusivityM2s = 1e-6;  // κ (CitcomS' `thermdiff`): velocities are in κ/R, times in R²/κ
    double temperatureK = 0.0;     // ΔT: temperatures times ΔT in K; 0: as written (nondimensional)
};

// True for a step of CitcomS output: a combined cap file `NAME.capNN.STEP` or its `.general`
// header, or an HDF5 step file `NAME.STEP.h5` (not the coordinates' `NAME.h5`).
bool isStep(const std::filesystem::path& path);

// The steps of a directory of CitcomS output, one path per step (its cap 00 file, or its .h5
// file) in step order; empty when it holds none.
std::vector<std::filesystem::path> stepsIn(const std::filesystem::path& directory);

// The step number in a step's name (`NAME.cap00.STEP`, `NAME.STEP.h5`).
long stepNumber(const std::filesystem::path& step);

// One step as the mesh resampler takes it: a piece per cap, points in km, the point arrays
// "temperature" (K with a ΔT, else nondimensional), "velocity" (3 components, Cartesian, m/s),
// "viscosity" (nondimensional, as written) and, from HDF5 output that has it, "pressure".
struct Step {
    std::vector<vtk::Piece> caps;
    std::optional<double> timeMyr;  // HDF5's `time` scaled; the ASCII caps carry none
    std::string format;             // formatName(step)
    size_t nx = 0, ny = 0, nz = 0;  // nodes of a cap
};

// The grid a run's caps resample onto by default, lat x r x lon: its own resolution, 4 (nx - 1)
// nodes around the equator, half as many from pole to pole (the cells are a little finer near the
// caps' corners), its nz radii; for a regional cap, nx x nz x ny.
std::array<size_t, 3> naturalGridSize(const Step& step);

// Reads a step. Scales' radius and diffusivity default to the values of the run's `/input`
// attributes (radius_km, thermdiff) when the HDF5 output has them and `scales` was not given.
// Throws raypc::Error naming the file and what is wrong: a cap file whose rows disagree with its
// header, a cap missing of 12, an HDF5 file without `coord`, arrays whose shapes disagree.
Step readStep(const std::filesystem::path& step, const Scales& scales, bool scalesGiven = false);

// The point arrays readStep gives for `step` (name and components), found without reading the
// values: what a series's later steps are checked against. Throws raypc::Error naming a file that
// is missing or not HDF5.
std::vector<std::pair<std::string, int>> stepArrays(const std::filesystem::path& step);

// The time of an HDF5 step (its root attribute `time`, scaled as readStep scales it); nullopt for
// the ASCII caps, which carry none.
std::optional<double> stepTimeMyr(const std::filesystem::path& step, const Scales& scales, bool scalesGiven = false);

// Every file readStep reads for `step`.
std::vector<std::filesystem::path> stepFiles(const std::filesystem::path& step);

// The form of `step`'s output: "CitcomS HDF5" or "CitcomS combined caps (ASCII)".
std::string formatName(const std::filesystem::path& step);

// The units of the arrays readStep gives.
std::string unitsOf(const std::string& array, const Scales& scales);

}  // namespace raypc::io::citcoms
