#include "render/map_projection.h"

#include "core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace raypc::render {
namespace {

constexpr double kPi = M_PI;
constexpr double kHalfPi = M_PI / 2;
constexpr double kRadians = M_PI / 180;
const double kSqrt2 = std::sqrt(2.0);


// Robinson's table (Robinson 1974, as d3-geo-projection gives it): per 5° of latitude from -5° to
// 90°, the length of the parallel and its distance from the equator; the distances scaled so that
// the map's height is 0.5072 of its width, as Robinson defined.
struct RobinsonRow {
    double x, y;
};
constexpr double kRobinsonYScale = 1.593415793900743;
constexpr RobinsonRow kRobinson[20] = {
    {0.9986, -0.0620}, {1.0000, 0.0000}, {0.9986, 0.0620}, {0.9954, 0.1240}, {0.9900, 0.1860},
    {0.9822, 0.2480},  {0.9730, 0.3100}, {0.9600, 0.3720}, {0.9427, 0.4340}, {0.9216, 0.4958},
    {0.8962, 0.5571},  {0.8679, 0.6176}, {0.8350, 0.6769}, {0.7986, 0.7346}, {0.7597, 0.7903},
    {0.7186, 0.8435},  {0.6732, 0.8936}, {0.6213, 0.9394}, {0.5722, 0.9761}, {0.5322, 1.0000}};

// The table between its rows at |phi|: Stirling's quadratic interpolation through the rows below,
// at and above (the first row, -5°, makes the equator's interpolation symmetric).
RobinsonRow robinsonAt(double absPhi)
{
    const double i = std::min(18.0, absPhi * 36 / kPi);
    const int i0 = static_cast<int>(std::floor(i));
    const double d = i - i0;
    const RobinsonRow& a = kRobinson[i0];
    const RobinsonRow& b = kRobinson[i0 + 1];
    const RobinsonRow& c = kRobinson[std::min(19, i0 + 2)];
    auto f = [d](double a, double b, double c) { return b + d * (c - a) / 2 + d * d * (c - 2 * b + a) / 2; };
    return {f(a.x, b.x, c.x), f(a.y, b.y, c.y) * kRobinsonYScale};
}

// The inverse of robinsonAt's y: |phi| (radians) at the distance `absY` from the equator. Between
// two rows Stirling's interpolation is a quadratic in the fraction d of the 5° step, increasing
// from the row's y (d = 0) to the next row's (d = 1): the row is found in the table and the
// quadratic solved in closed form (a map's every pixel is inverted: 60 bisections per pixel made
// a 4096² Robinson map take 20 s).
double robinsonLatitude(double absY)
{
    const double t = std::min(absY / kRobinsonYScale, kRobinson[19].y);
    int i0 = 0;  // the interval [i0 · 5°, (i0 + 1) · 5°] spans rows i0 + 1 .. i0 + 2 of the table
    while (i0 < 17 && kRobinson[i0 + 2].y < t)
        ++i0;
    const double a = kRobinson[i0].y, b = kRobinson[i0 + 1].y, c = kRobinson[i0 + 2].y;
    const double qa = (c - 2 * b + a) / 2, qb = (c - a) / 2, rhs = t - b;
    // qa d² + qb d = rhs, in the form that stays exact as qa goes to 0.
    const double d = 2 * rhs / (qb + std::sqrt(std::max(0.0, qb * qb + 4 * qa * rhs)));
    return (i0 + std::clamp(d, 0.0, 1.0)) * kPi / 36;
}

// Mollweide's auxiliary angle theta: 2 theta + sin 2 theta = pi sin phi (Newton's method).
double mollweideTheta(double phi)
{
    if (std::abs(phi) >= kHalfPi - 1e-12)
        return std::copysign(kHalfPi, phi);
    const double target = kPi * std::sin(phi);
    double t = phi;  // t = 2 theta
    for (int i = 0; i < 60; ++i) {
        const double delta = (t + std::sin(t) - target) / (1 + std::cos(t));
        t -= delta;
        if (std::abs(delta) < 1e-14)
            break;
    }
    return t / 2;
}

double wrapLambda(double lambda)
{
    if (lambda > kPi)
        lambda -= 2 * kPi;
    else if (lambda < -kPi)
        lambda += 2 * kPi;
    return lambda;
}

}  // namespace

Projector::Projector(MapProjection projection, double centralMeridianDeg, double centralLatitudeDeg)
    : m_projection(projection), m_lambda0(centralMeridianDeg * kRadians), m_phi0(centralLatitudeDeg * kRadians),
      m_cosPhi0(std::cos(m_phi0)), m_sinPhi0(std::sin(m_phi0))
{
    if (!(centralMeridianDeg >= -180 && centralMeridianDeg <= 180))
        fail("central meridian {}° is outside [-180, 180]", centralMeridianDeg);
    if (!(centralLatitudeDeg >= -90 && centralLatitudeDeg <= 90))
        fail("central latitude {}° is outside [-90, 90]", centralLatitudeDeg);
}

std::array<double, 2> Projector::rotate(double lambda, double phi) const
{
    lambda = wrapLambda(lambda - m_lambda0);
    if (m_phi0 == 0)
        return {lambda, phi};
    // The centre's latitude to the equator: a rotation about the axis through (0°, ±90° E).
    const double x = std::cos(phi) * std::cos(lambda), y = std::cos(phi) * std::sin(lambda), z = std::sin(phi);
    const double xr = x * m_cosPhi0 + z * m_sinPhi0, zr = z * m_cosPhi0 - x * m_sinPhi0;
    return {std::atan2(y, xr), std::asin(std::clamp(zr, -1.0, 1.0))};
}

std::array<double, 2> Projector::unrotate(double lambda, double phi) const
{
    if (m_phi0 != 0) {
        const double xr = std::cos(phi) * std::cos(lambda), y = std::cos(phi) * std::sin(lambda), zr = std::sin(phi);
        const double x = xr * m_cosPhi0 - zr * m_sinPhi0, z = zr * m_cosPhi0 + xr * m_sinPhi0;
        lambda = std::atan2(y, x);
        phi = std::asin(std::clamp(z, -1.0, 1.0));
    }
    lambda = wrapLambda(lambda + m_lambda0);
    if (lambda >= kPi)
        lambda -= 2 * kPi;
    return {lambda, phi};
}

std::optional<std::array<double, 2>> Projector::forward(double lonDeg, double latDeg) const
{
    const auto [lambda, phi] = rotate(lonDeg * kRadians, latDeg * kRadians);
    switch (m_projection) {
    case MapProjection::Equirectangular: return std::array{lambda, phi};
    case MapProjection::Mollweide: {
        const double theta = mollweideTheta(phi);
        return std::array{2 * kSqrt2 / kPi * lambda * std::cos(theta), kSqrt2 * std::sin(theta)};
    }
    case MapProjection::Hammer: {
        // The azimuthal equal-area projection of (lambda / 2, phi), stretched twice along x.
        const double k = std::sqrt(2 / (1 + std::cos(phi) * std::cos(lambda / 2)));
        return std::array{2 * k * std::cos(phi) * std::sin(lambda / 2), k * std::sin(phi)};
    }
    case MapProjection::Robinson: {
        const RobinsonRow r = robinsonAt(std::abs(phi));
        return std::array{lambda * r.x, std::copysign(r.y, phi)};
    }
    case MapProjection::Orthographic:
        if (std::cos(phi) * std::cos(lambda) < 0)
            return std::nullopt;
        return std::array{std::cos(phi) * std::sin(lambda), std::sin(phi)};
    }
    return std::nullopt;
}

std::optional<std::array<double, 2>> Projector::inverse(double x, double y) const
{
    double lambda = 0, phi = 0;
    switch (m_projection) {
    case MapProjection::Equirectangular:
        if (std::abs(x) > kPi * (1 + 1e-9) || std::abs(y) > kHalfPi * (1 + 1e-9))
            return std::nullopt;
        lambda = std::clamp(x, -kPi, kPi);
        phi = std::clamp(y, -kHalfPi, kHalfPi);
        break;
    case MapProjection::Mollweide: {
        const double a = x / (2 * kSqrt2), b = y / kSqrt2;
        if (a * a + b * b > 1 + 1e-9)
            return std::nullopt;
        const double theta = std::asin(std::clamp(b, -1.0, 1.0));
        const double c = std::cos(theta);
        lambda = c > 1e-15 ? kPi * x / (2 * kSqrt2 * c) : 0;
        phi = std::asin(std::clamp((2 * theta + std::sin(2 * theta)) / kPi, -1.0, 1.0));
        break;
    }
    case MapProjection::Hammer: {
        const double a = x / 2;
        const double z = std::sqrt(a * a + y * y);
        if (z > kSqrt2 * (1 + 1e-9))
            return std::nullopt;
        // The azimuthal equal-area projection's inverse at (x / 2, y); the longitude doubled.
        const double c = 2 * std::asin(std::min(1.0, z / 2));
        const double sc = std::sin(c), cc = std::cos(c);
        lambda = 2 * std::atan2(a * sc, z * cc);
        phi = std::asin(std::clamp(z > 0 ? y * sc / z : y, -1.0, 1.0));
        break;
    }
    case MapProjection::Robinson: {
        const double yMax = kRobinson[19].y * kRobinsonYScale;
        if (std::abs(y) > yMax * (1 + 1e-9))
            return std::nullopt;
        phi = std::copysign(robinsonLatitude(std::abs(y)), y);
        lambda = x / robinsonAt(std::abs(phi)).x;
        if (std::abs(lambda) > kPi * (1 + 1e-9))
            return std::nullopt;
        break;
    }
    case MapProjection::Orthographic: {
        const double rho2 = x * x + y * y;
        if (rho2 > 1 + 1e-9)
            return std::nullopt;
        lambda = std::atan2(x, std::sqrt(std::max(0.0, 1 - rho2)));
        phi = std::asin(std::clamp(y, -1.0, 1.0));
        break;
    }
    }
    const auto [lon, lat] = unrotate(lambda, phi);
    return std::array{lon / kRadians, lat / kRadians};
}

Projector::Extent Projector::extent() const
{
    switch (m_projection) {
    case MapProjection::Equirectangular: return {kPi, kHalfPi};
    case MapProjection::Mollweide:
    case MapProjection::Hammer: return {2 * kSqrt2, kSqrt2};
    case MapProjection::Robinson: return {kPi * kRobinson[1].x, kRobinson[19].y * kRobinsonYScale};
    case MapProjection::Orthographic: return {1, 1};
    }
    return {1, 1};
}

}  // namespace raypc::render
