// The server side of docs/protocol.md (version 1): parsing client WebSocket messages, building
// server text messages, and the binary frame layout. Pure functions without network types, so the
// codec is tested on its own.
//
// Thread safety: all functions are reentrant.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace raypc::server {

inline constexpr int kProtocolVersion = 1;
inline constexpr size_t kMaxClientMessageBytes = 256 * 1024;  // larger text messages get an error reply
inline constexpr size_t kMaxHttpBodyBytes = 1024 * 1024;      // larger HTTP bodies get 413

struct HelloMessage {
    int protocol = 0;
};
// How a session renders a state (docs/protocol.md, the state message):
// - still: progressive passes at the state's level (level 0 when "auto") until state.passes;
// - interactive (the user drags): one pass at the finest level that fits state.timeBudgetMs, at
//   1/2 or 1/4 of the size per axis when even the coarsest level misses it;
// - playback (a step of playback, shown for timeBudgetMs): the level chosen as for interactive, then
//   progressive passes at that level until state.passes or the next state.
enum class FrameMode { still, interactive, playback };
const char* frameModeName(FrameMode mode);

struct StateMessage {
    int64_t id = 0;
    nlohmann::json state;  // the render state document, validated later against the dataset
    FrameMode mode = FrameMode::still;
};
struct CancelMessage {};
struct PingMessage {
    int64_t id = 0;
};
using ClientMessage = std::variant<HelloMessage, StateMessage, CancelMessage, PingMessage>;

// Parses one text message. Throws raypc::Error with a message for the client on oversized input,
// malformed JSON, a non-object, an unknown or missing `type`, or a missing/ill-typed field (an `id`
// outside the signed 64-bit range included: ids are echoed exactly, never wrapped).
ClientMessage parseClientMessage(std::string_view text);

// Server text messages.
std::string helloReply(const std::string& sessionId);
std::string pongReply(int64_t id);
std::string errorReply(const std::string& message, std::optional<int64_t> id = std::nullopt);
// The linked state a program set (POST /api/link, server/linked_state.h), for the UI to apply.
std::string linkMessage(uint64_t version, const nlohmann::json& state);

// A binary frame: u32 LE header length, UTF-8 JSON header, JPEG bytes, depth as float32 LE.
// The header's jpegBytes/depthBytes/depthWidth/depthHeight are filled in here.
std::string encodeFrame(nlohmann::json header, std::span<const uint8_t> jpeg, std::span<const float> depth,
                        int depthWidth, int depthHeight);

struct DecodedFrame {
    nlohmann::json header;
    std::string_view jpeg;
    std::vector<float> depth;
};
// The inverse of encodeFrame (for tests and the test client). Throws raypc::Error on a bad layout.
DecodedFrame decodeFrame(std::string_view bytes);
// Only the header of a frame (cheap: the image and depth are not touched). Throws like decodeFrame.
nlohmann::json frameHeader(std::string_view bytes);

// Downsamples a width x height depth map by `factor` along both axes (ceil sizes): each block keeps
// its nearest finite depth, or +infinity if it has none.
std::vector<float> downsampleDepth(std::span<const float> depthKm, int width, int height, int factor,
                                   int& outWidth, int& outHeight);

}  // namespace raypc::server
