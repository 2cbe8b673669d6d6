// Map projections of the sphere for depth-slice maps (`raypc map`, the UI's map panel): the
// formulas of d3-geo and d3-geo-projection, which the UI uses, so that a figure and the panel place
// every point alike. Tested against d3's own values at a set of points
// (tests/data/projections/d3-projections.json, written once by node).
//
// Coordinates: longitude and latitude in degrees; projected x, y at unit scale (the sphere of
// radius 1), y up. A projection is centred on a meridian (and, for the orthographic one, a
// latitude): the centre maps to (0, 0).
//
// Thread safety: immutable.
#pragma once

#include "state/view_types.h"

#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace raypc::render {

// The projections' names are the state's (state/view_types.h).
using state::MapProjection;

class Projector {
public:
    // Throws raypc::Error for a centre outside [-180, 180] x [-90, 90] degrees.
    Projector(MapProjection projection, double centralMeridianDeg, double centralLatitudeDeg = 0);

    // (x, y) of a point; std::nullopt where the projection does not show it (the far hemisphere of
    // the orthographic projection).
    std::optional<std::array<double, 2>> forward(double lonDeg, double latDeg) const;
    // (lon, lat) of a projected point, lon in [-180, 180); std::nullopt outside the projected sphere.
    std::optional<std::array<double, 2>> inverse(double x, double y) const;

    // The projected sphere's extent: [xMin, xMax] x [yMin, yMax] (it is symmetric about (0, 0)).
    struct Extent {
        double xMax, yMax;
    };
    Extent extent() const;

    MapProjection projection() const { return m_projection; }

private:
    // Rotation of a point into (out of) the projection's frame, radians.
    std::array<double, 2> rotate(double lambda, double phi) const;
    std::array<double, 2> unrotate(double lambda, double phi) const;

    MapProjection m_projection;
    double m_lambda0, m_phi0;  // radians
    double m_cosPhi0, m_sinPhi0;
};

}  // namespace raypc::render
