// The bounds `raypc serve` promises (docs/reliability.md, Server): one place for every limit on
// connections, sessions, memory, queues and screenshots, so that the errors, the docs and the tests
// quote the same numbers. The first group can be changed on the command line (cmd_serve.cpp).
//
// Thread safety: plain values, copied into the server at start.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>

namespace raypc::server {

// What one pixel of a session's or a screenshot's image costs while it renders: the frame buffer
// (RGBA and depth sums, depth counts, the pass scratch: 42 bytes) plus the transient copies made to
// encode a frame (averaged RGBA, 8-bit RGBA, depth: 24 bytes), rounded up.
inline constexpr size_t kFrameBytesPerPixel = 72;

// The largest image of a session's state (stereo: both eyes together); larger ones get an error
// naming /api/screenshot. A frame buffer of 4096² takes about 0.7 GB with its scratch.
inline constexpr int64_t kMaxSessionPixels = int64_t(4096) * 4096;
// Beyond this a WebSocket message closes the connection (code 1009); between the protocol's
// kMaxClientMessageBytes (protocol.h) and this it gets an error reply and the connection stays.
inline constexpr size_t kHardMessageLimit = 4 * 1024 * 1024;

struct ServerLimits {
    // Open TCP connections (HTTP and WebSocket together); one more is answered 503 and closed.
    size_t maxConnections = 256;
    // WebSocket sessions; each has a render thread. One more is refused at the upgrade (503).
    size_t maxSessions = 16;
    // The frame memory of every session's newest state together (width x height x
    // kFrameBytesPerPixel); a state that does not fit gets an error and the previous state stays.
    size_t sessionFrameBytes = size_t(2) << 30;
    // The frames a session keeps of its current state, rendered ahead for playback
    // (server/frame_cache.h), each session's; `--frame-cache`.
    size_t frameCacheBytes = size_t(256) << 20;

    // Text replies (errors, pongs) waiting for a client that does not read; beyond this the
    // connection is closed. Frames do not count: only the newest waits (the older one is dropped).
    size_t maxQueuedTextBytes = 1 << 20;
    // A frame or message the client has not taken within this time closes the connection.
    std::chrono::milliseconds writeStall{30'000};
    // While states keep arriving, a session's work in flight is cancelled by a newer state only until
    // it has gone this long without a frame; then the newer state waits for that frame, so that every
    // session gets a frame at least every frameGuarantee plus one pass, however fast it sends.
    std::chrono::milliseconds frameGuarantee{250};

    // POST /api/screenshot: image size, and passes times pixels (the work of one screenshot:
    // 1024 x 1024 at 256 passes, 4096 x 4096 at 16).
    int64_t maxScreenshotPixels = int64_t(4096) * 4096;
    int maxScreenshotPasses = 1024;
    int64_t maxScreenshotPixelPasses = int64_t(1024) * 1024 * 256;
    // Requests of the one-at-a-time lanes (screenshots; statistics over time; maps and sections) that may wait behind
    // the one running; more are answered 503.
    size_t maxWaitingJobs = 4;

    // Accepting when the process is out of file descriptors: wait this long, doubling up to the
    // maximum, instead of retrying at once.
    std::chrono::milliseconds acceptBackoffMin{50}, acceptBackoffMax{1000};
};

}  // namespace raypc::server
