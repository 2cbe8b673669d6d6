#include "core/progress.h"

#include "core/clock.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

namespace raypc {

bool Progress::interactive()
{
    const char* ci = std::getenv("CI");
    return ::isatty(STDERR_FILENO) && !(ci && *ci && std::string(ci) != "false");
}

Progress::Progress(std::string label, int64_t total, std::string unit)
    : m_label(std::move(label)), m_unit(std::move(unit)), m_total(total),
      m_start(std::chrono::steady_clock::now()), m_lastDraw(m_start), m_interactive(interactive())
{
}

Progress::~Progress() { finish(); }

void Progress::advance(int64_t n)
{
    const int64_t done = m_done.fetch_add(n) + n;
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard lock(m_mutex);
    if (m_finished)
        return;
    if (m_interactive) {
        if (now - m_lastDraw < std::chrono::milliseconds(100) && done < m_total)
            return;
        m_lastDraw = now;
        draw(done, false);
    } else {
        const int decile = m_total > 0 ? static_cast<int>(10 * done / m_total) : 10;
        if (decile != m_lastDecile && decile < 10) {
            m_lastDecile = decile;
            draw(done, false);
        }
    }
}

void Progress::finish()
{
    std::lock_guard lock(m_mutex);
    if (m_finished)
        return;
    m_finished = true;
    draw(m_done.load(), true);
}

void Progress::draw(int64_t done, bool final)
{
    const double seconds = secondsSince(m_start);
    const double rate = seconds > 0 ? done / seconds : 0.0;
    const double fraction = m_total > 0 ? static_cast<double>(done) / m_total : 1.0;
    const double eta = rate > 0 ? (m_total - done) / rate : 0.0;
    if (m_interactive) {
        constexpr int kWidth = 30;
        const int filled = static_cast<int>(fraction * kWidth + 0.5);
        std::string bar(filled, '#');
        bar.resize(kWidth, '.');
        std::fprintf(stderr, "\r%s [%s] %lld/%lld %s  %.2f %s/s  %s %.0f s   %s", m_label.c_str(),
                     bar.c_str(), static_cast<long long>(done), static_cast<long long>(m_total),
                     m_unit.c_str(), rate, m_unit.c_str(), final ? "took" : "ETA",
                     final ? seconds : eta, final ? "\n" : "");
    } else {
        std::fprintf(stderr, "%s: %lld/%lld %s (%.0f%%), %.2f %s/s, %s %.1f s\n", m_label.c_str(),
                     static_cast<long long>(done), static_cast<long long>(m_total), m_unit.c_str(),
                     100.0 * fraction, rate, m_unit.c_str(), final ? "took" : "ETA",
                     final ? seconds : eta);
    }
    std::fflush(stderr);
}

}  // namespace raypc
