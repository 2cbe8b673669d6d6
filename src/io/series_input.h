// The inputs of a series, whatever their format, as the dataset pipeline (preprocess.h) reads them:
// netCDF files (one step each, netcdf_reader.h), or the output of a deal.II-based model such as
// ASPECT (a .pvd collection of .pvtu records of .vtu pieces, vtk_xml.h), whose steps are resampled
// onto a spherical grid (mesh_resample.h) when read. Everything after reading is the same pipeline.
//
// ASPECT's variables (docs/format.md, "ASPECT's output"): scalars keep their names and get ASPECT's
// units where the name is one ASPECT writes (T: K, p: Pa, density: kg/m^3, viscosity: Pa s, …);
// `velocity` (m/year) becomes vx, vy, vz in m/s, the contest's unit, from which the radial velocity
// is derived as for the contest data; other 3-component arrays become NAME_x, NAME_y, NAME_z;
// arrays of other sizes (tensors) are left out and named in the log.
#pragma once

#include "io/netcdf_reader.h"

#include <filesystem>
#include <string>
#include <vector>

namespace raypc::io {

struct SeriesListing {
    std::vector<std::filesystem::path> steps;  // netCDF files, or VTK steps (.pvtu records or .vtu pieces)
    // Each step's time (Myr) when the inputs give it (a .pvd's `timestep`, in options.timeUnit);
    // empty otherwise (steps are then dt_myr apart).
    std::vector<double> timesMyr;
    bool vtk = false;            // a mesh resampled when read: VTK XML or CitcomS output
    const char* kind = "netcdf";  // "netcdf", "vtk" or "citcoms"
    std::filesystem::path collection;  // the .pvd the steps come from, if any
};

// Expands the arguments into steps: netCDF files and directories of *.nc (natural order, as
// listSnapshotFiles; a file whose variables have a time dimension longer than 1 is that many steps,
// named FILE#0, FILE#1, … in messages and manifests); a .pvd collection (its steps in time order, with their times); a directory
// holding solution.pvd (ASPECT's output directory) or exactly one .pvd; .pvtu records or .vtu
// pieces given one by one (natural order). Throws raypc::Error naming an argument that is none of
// these, a .pvd naming a missing file, or a mix of netCDF and VTK inputs.
SeriesListing listSeries(const std::vector<std::filesystem::path>& args, const ReaderOptions& options);

// True for a VTK step (.pvtu or .vtu).
bool isVtkStep(const std::filesystem::path& step);
// True for a step whose mesh is resampled when read: a VTK step or CitcomS output (citcoms.h).
bool isMeshStep(const std::filesystem::path& step);

// readHeader / readSnapshot for any step. A VTK step's header reads the step's whole mesh to choose
// the grid unless options.targetGrid is set (then only its record, for the variables); its snapshot
// reads the pieces in parallel and resamples them onto options.targetGrid (or the chosen grid).
// Grid points in no cell are an error naming the first unless options.fillMissing (then the mean
// of their shell). Throws raypc::Error naming the file and what is wrong.
FileHeader readStepHeader(const std::filesystem::path& step, const ReaderOptions& options);
grid::Snapshot readStep(const std::filesystem::path& step, const ReaderOptions& options);

// Every file readStep reads for `step`: the file itself (of a `FILE#K` step, FILE), and a .pvtu's
// pieces. Throws raypc::Error
// as readStep does for a .pvtu that cannot be read.
std::vector<std::filesystem::path> stepSourceFiles(const std::filesystem::path& step);

}  // namespace raypc::io
