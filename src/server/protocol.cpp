#include "server/protocol.h"

#include "core/error.h"
#include "core/json_input.h"
#include "server/protocol_schema.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <tuple>

namespace raypc::server {

using nlohmann::json;

namespace {

// Ids and versions are signed 64-bit integers: they are echoed exactly, so a value outside that range
// (e.g. 18446744073709551615, which would come back as -1) is refused, not wrapped.
int64_t integerField(const json& message, const char* type, const char* key)
{
    const auto it = message.find(key);
    if (it == message.end())
        fail("{}: missing field '{}'", type, key);
    if (it->is_number_unsigned()) {
        const uint64_t v = it->get<uint64_t>();
        if (v <= uint64_t(std::numeric_limits<int64_t>::max()))
            return int64_t(v);
        fail("{}: field '{}' is {}, out of range (a signed 64-bit integer: at most {})", type, key, v,
             std::numeric_limits<int64_t>::max());
    }
    if (it->is_number_integer())
        return it->get<int64_t>();
    if (it->is_number_float()) {
        const double v = it->get<double>();
        if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 9e15)
            return int64_t(v);
        if (std::isfinite(v) && v == std::floor(v))
            fail("{}: field '{}' is {}, out of range (a signed 64-bit integer; written with a fraction or "
                 "exponent, at most 9e15 in magnitude)",
                 type, key, jsonExcerpt(*it, 40));
    }
    fail("{}: field '{}' must be an integer, found {}", type, key, jsonExcerpt(*it, 40));
}

// Keys outside the description of the message (server/protocol_schema.cpp, `definition`) are refused.
void rejectUnknownKeys(const json& message, const char* type, std::string_view definition)
{
    const std::vector<std::string>& known = messageKeys(definition);
    for (const auto& item : message.items())
        if (std::find(known.begin(), known.end(), item.key()) == known.end())
            fail("{}: unknown field '{}'", type, item.key());
}

void putU32(std::string& out, uint32_t v)
{
    for (int i = 0; i < 4; ++i)
        out.push_back(char((v >> (8 * i)) & 0xff));
}

}  // namespace

const char* frameModeName(FrameMode mode)
{
    switch (mode) {
    case FrameMode::interactive: return "interactive";
    case FrameMode::playback: return "playback";
    case FrameMode::still: break;
    }
    return "still";
}

ClientMessage parseClientMessage(std::string_view text)
{
    if (text.size() > kMaxClientMessageBytes)
        fail("message of {} bytes is over the limit of {} bytes", text.size(), kMaxClientMessageBytes);
    const json message = parseJsonInput(text, "message");
    if (!message.is_object())
        fail("expected a JSON object with a 'type', found {}", message.type_name());
    const auto typeIt = message.find("type");
    if (typeIt == message.end())
        fail("missing field 'type'");
    if (!typeIt->is_string())
        fail("field 'type' must be a string");
    const std::string type = typeIt->get<std::string>();
    if (type == "hello") {
        rejectUnknownKeys(message, "hello", "ClientHello");
        return HelloMessage{int(std::clamp<int64_t>(integerField(message, "hello", "protocol"), -1, 1 << 30))};
    }
    if (type == "state") {
        rejectUnknownKeys(message, "state", "ClientState");
        StateMessage m;
        m.id = integerField(message, "state", "id");
        const auto st = message.find("state");
        if (st == message.end())
            fail("state: missing field 'state'");
        if (!st->is_object())
            fail("state: field 'state' must be an object (docs/state.md)");
        m.state = *st;
        const auto flag = [&](const char* name) {
            const auto in = message.find(name);
            if (in == message.end())
                return false;
            if (!in->is_boolean())
                fail("state: field '{}' must be true or false", name);
            return in->get<bool>();
        };
        const bool interactive = flag("interactive"), playback = flag("playback");
        if (interactive && playback)
            fail("state: 'interactive' and 'playback' cannot both be true");
        m.mode = interactive ? FrameMode::interactive : playback ? FrameMode::playback : FrameMode::still;
        return m;
    }
    if (type == "cancel") {
        rejectUnknownKeys(message, "cancel", "ClientCancel");
        return CancelMessage{};
    }
    if (type == "ping") {
        rejectUnknownKeys(message, "ping", "ClientPing");
        return PingMessage{integerField(message, "ping", "id")};
    }
    fail("unknown message type '{}'; expected hello, state, cancel or ping", type.substr(0, 64));
}

std::string helloReply(const std::string& sessionId)
{
    return json{{"type", "hello"}, {"protocol", kProtocolVersion}, {"session", sessionId}}.dump();
}

std::string pongReply(int64_t id)
{
    return json{{"type", "pong"}, {"id", id}}.dump();
}

std::string linkMessage(uint64_t version, const json& state)
{
    return json{{"type", "link"}, {"version", version}, {"state", state}}.dump(-1, ' ', false,
                                                                               json::error_handler_t::replace);
}

std::string errorReply(const std::string& message, std::optional<int64_t> id)
{
    json j{{"type", "error"}, {"message", message}};
    if (id)
        j["id"] = *id;
    // Messages may quote client input: never let invalid UTF-8 make dump() throw.
    return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string encodeFrame(json header, std::span<const uint8_t> jpeg, std::span<const float> depth, int depthWidth,
                        int depthHeight)
{
    RAYPC_CHECK_EQ(depth.size(), size_t(depthWidth) * size_t(depthHeight));
    header["jpegBytes"] = jpeg.size();
    header["depthWidth"] = depthWidth;
    header["depthHeight"] = depthHeight;
    header["depthBytes"] = depth.size() * sizeof(float);
    const std::string text = header.dump(-1, ' ', false, json::error_handler_t::replace);
    std::string out;
    out.reserve(4 + text.size() + jpeg.size() + depth.size() * 4);
    putU32(out, uint32_t(text.size()));
    out += text;
    out.append(reinterpret_cast<const char*>(jpeg.data()), jpeg.size());
    static_assert(std::numeric_limits<float>::is_iec559);
    for (float d : depth) {
        uint32_t bits;
        std::memcpy(&bits, &d, 4);
        putU32(out, bits);
    }
    return out;
}

namespace {

// The header's length and the parsed header of a frame.
std::pair<uint32_t, json> readFrameHeader(std::string_view bytes)
{
    if (bytes.size() < 4)
        fail("frame: {} bytes, too short for the header length", bytes.size());
    uint32_t headerBytes = 0;
    for (int i = 0; i < 4; ++i)
        headerBytes |= uint32_t(uint8_t(bytes[size_t(i)])) << (8 * i);
    if (bytes.size() - 4 < headerBytes)
        fail("frame: header of {} bytes does not fit in {} bytes", headerBytes, bytes.size());
    try {
        return {headerBytes, json::parse(bytes.substr(4, headerBytes))};
    } catch (const json::exception& e) {
        fail("frame: header is not JSON: {}", e.what());
    }
}

}  // namespace

json frameHeader(std::string_view bytes)
{
    return readFrameHeader(bytes).second;
}

DecodedFrame decodeFrame(std::string_view bytes)
{
    DecodedFrame f;
    uint32_t headerBytes = 0;
    std::tie(headerBytes, f.header) = readFrameHeader(bytes);
    const auto jpegBytes = f.header.value("jpegBytes", size_t(0));
    const auto depthBytes = f.header.value("depthBytes", size_t(0));
    const size_t rest = bytes.size() - 4 - headerBytes;
    if (jpegBytes + depthBytes != rest)
        fail("frame: jpegBytes {} + depthBytes {} != {} bytes after the header", jpegBytes, depthBytes, rest);
    if (depthBytes % 4 != 0)
        fail("frame: depthBytes {} is not a multiple of 4", depthBytes);
    f.jpeg = bytes.substr(4 + headerBytes, jpegBytes);
    f.depth.resize(depthBytes / 4);
    std::memcpy(f.depth.data(), bytes.data() + 4 + headerBytes + jpegBytes, depthBytes);
    return f;
}

std::vector<float> downsampleDepth(std::span<const float> depthKm, int width, int height, int factor, int& outWidth,
                                   int& outHeight)
{
    RAYPC_CHECK(factor >= 1 && width >= 0 && height >= 0);
    RAYPC_CHECK_EQ(depthKm.size(), size_t(width) * size_t(height));
    outWidth = (width + factor - 1) / factor;
    outHeight = (height + factor - 1) / factor;
    std::vector<float> out(size_t(outWidth) * size_t(outHeight), std::numeric_limits<float>::infinity());
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const float d = depthKm[size_t(y) * size_t(width) + size_t(x)];
            float& o = out[size_t(y / factor) * size_t(outWidth) + size_t(x / factor)];
            if (std::isfinite(d) && d < o)
                o = d;
        }
    return out;
}

}  // namespace raypc::server
