// Pathline sets and their seeds as files for other tools: CSV, VTK XML PolyData (.vtp) and legacy
// VTK (.vtk), as `raypc export` writes them (ParaView opens both VTK forms).
#pragma once

#include "analysis/pathlines.h"

#include <string>

namespace raypc::analysis {

// One row per point: line, point, x, y, z, lat, lon, radius, time, age, then the line's attributes.
std::string pathlinesCsv(const PathlineSet& set);
// One row per seed (the first point of each line): kind, value, coordinates, then attributes.
std::string criticalPointsCsv(const PathlineSet& set);
// VTK PolyData, XML (.vtp, ASCII) or legacy ASCII (.vtk): lines with point data time/age and cell
// data for every attribute; critical points as vertices with their attributes as point data.
std::string pathlinesVtp(const PathlineSet& set);
std::string pathlinesLegacyVtk(const PathlineSet& set);
std::string criticalPointsVtp(const PathlineSet& set);
std::string criticalPointsLegacyVtk(const PathlineSet& set);

}  // namespace raypc::analysis
