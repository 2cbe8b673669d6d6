#include "server/protocol.h"

#include "core/error.h"
#include "server/protocol_schema.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

namespace raypc::server {
namespace {

using nlohmann::json;

template <typename T>
T parseAs(const std::string& text)
{
    const ClientMessage m = parseClientMessage(text);
    EXPECT_TRUE(std::holds_alternative<T>(m)) << text;
    return std::get<T>(m);
}

std::string errorOf(const std::string& text)
{
    try {
        parseClientMessage(text);
    } catch (const Error& e) {
        return e.what();
    }
    return "<accepted>";
}

// The client messages' parser and their description (protocol_schema.cpp, from which the UI's
// types come) agree: a message with every key the description lists is accepted, one with a key it
// does not list is refused, and so is one without a key the description requires.
TEST(ProtocolCodec, ParserAcceptsWhatTheDescriptionSays)
{
    const json schema = protocolJsonSchema()["definitions"];
    const std::map<std::string, json> full = {
        {"ClientHello", {{"type", "hello"}, {"protocol", 1}}},
        {"ClientState", {{"type", "state"}, {"id", 3}, {"state", {{"version", 1}}}, {"interactive", false}, {"playback", true}}},
        {"ClientCancel", {{"type", "cancel"}}},
        {"ClientPing", {{"type", "ping"}, {"id", 4}}},
    };
    for (const auto& [title, message] : full) {
        const json& d = schema.at(title);
        std::vector<std::string> keys;
        for (const auto& [key, value] : d["properties"].items())
            keys.push_back(key);
        std::vector<std::string> given;
        for (const auto& [key, value] : message.items())
            given.push_back(key);
        std::sort(keys.begin(), keys.end());
        EXPECT_EQ(given, keys) << title << ": the test's message has every key the description lists";
        EXPECT_EQ(errorOf(message.dump()), "<accepted>") << title;
        json extra = message;
        extra["colour"] = "red";
        EXPECT_NE(errorOf(extra.dump()).find("unknown field 'colour'"), std::string::npos) << title;
        for (const auto& key : d["required"]) {
            if (key == "type")
                continue;
            json missing = message;
            missing.erase(key.get<std::string>());
            EXPECT_NE(errorOf(missing.dump()), "<accepted>") << title << " without " << key;
        }
    }
}

TEST(ProtocolCodec, ParsesEachClientMessage)
{
    EXPECT_EQ(parseAs<HelloMessage>(R"({"type": "hello", "protocol": 1})").protocol, 1);
    EXPECT_EQ(parseAs<HelloMessage>(R"({"type": "hello", "protocol": 7})").protocol, 7);
    const auto s = parseAs<StateMessage>(R"({"type": "state", "id": 17, "state": {"version": 1, "step": 2}, "interactive": true})");
    EXPECT_EQ(s.id, 17);
    EXPECT_EQ(s.mode, FrameMode::interactive);
    EXPECT_EQ(s.state["step"], 2);
    EXPECT_EQ(parseAs<StateMessage>(R"({"type": "state", "id": 3, "state": {}})").mode, FrameMode::still);
    EXPECT_EQ(parseAs<StateMessage>(R"({"type": "state", "id": 4, "state": {}, "playback": true})").mode, FrameMode::playback);
    EXPECT_EQ(parseAs<StateMessage>(R"({"type": "state", "id": 5, "state": {}, "playback": false, "interactive": false})").mode,
              FrameMode::still);
    parseAs<CancelMessage>(R"({"type": "cancel"})");
    EXPECT_EQ(parseAs<PingMessage>(R"({"type": "ping", "id": 99})").id, 99);
    EXPECT_EQ(parseAs<PingMessage>(R"({"type": "ping", "id": 5.0})").id, 5);
}

// Ids are echoed exactly: the whole signed 64-bit range passes, anything beyond is refused (never
// wrapped: 18446744073709551615 used to come back as -1).
TEST(ProtocolCodec, IdsKeepTheirValueOrAreRefused)
{
    EXPECT_EQ(parseAs<PingMessage>(R"({"type": "ping", "id": 9223372036854775807})").id, INT64_MAX);
    EXPECT_EQ(parseAs<PingMessage>(R"({"type": "ping", "id": -9223372036854775808})").id, INT64_MIN);
    EXPECT_EQ(pongReply(INT64_MAX), R"({"id":9223372036854775807,"type":"pong"})");
    for (const char* id : {"18446744073709551615", "9223372036854775808"}) {
        const std::string e = errorOf(std::string(R"({"type": "ping", "id": )") + id + "}");
        EXPECT_NE(e.find(std::string("ping: field 'id' is ") + id + ", out of range"), std::string::npos) << e;
    }
    EXPECT_NE(errorOf(R"({"type": "state", "id": 18446744073709551615, "state": {}})").find("state: field 'id'"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "ping", "id": -9223372036854775809})").find("out of range"), std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "ping", "id": 1e300})").find("out of range"), std::string::npos);
}

TEST(ProtocolCodec, RejectsMalformedJson)
{
    EXPECT_NE(errorOf(R"({"type": "hello", )").find("message: not valid JSON"), std::string::npos);
    EXPECT_NE(errorOf("").find("message: not valid JSON"), std::string::npos);
    EXPECT_NE(errorOf("\xff\xfe").find("message: not valid JSON"), std::string::npos);
    // Nesting is bounded before parsing (deep JSON crashed the recursive parser): 100 000 levels in
    // 200 KB, under the message limit.
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    EXPECT_NE(errorOf(R"({"type": "ping", "id": )" + deep + "}").find("nested deeper than 64 levels"), std::string::npos);
    EXPECT_LT(errorOf(R"({"type": "ping", "id": )" + deep + "}").size(), 200u);
    EXPECT_NE(errorOf("[1, 2]").find("expected a JSON object"), std::string::npos);
    EXPECT_NE(errorOf("42").find("expected a JSON object"), std::string::npos);
}

TEST(ProtocolCodec, RejectsUnknownTypeAndKeys)
{
    EXPECT_NE(errorOf(R"({"type": "explode"})").find("unknown message type 'explode'"), std::string::npos);
    EXPECT_NE(errorOf(R"({"type": 3})").find("'type' must be a string"), std::string::npos);
    EXPECT_NE(errorOf(R"({"kind": "hello"})").find("missing field 'type'"), std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "cancel", "now": true})").find("unknown field 'now'"), std::string::npos);
}

TEST(ProtocolCodec, RejectsMissingOrIllTypedFields)
{
    EXPECT_NE(errorOf(R"({"type": "hello"})").find("hello: missing field 'protocol'"), std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "hello", "protocol": "1"})").find("must be an integer"), std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "state", "state": {}})").find("state: missing field 'id'"), std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "state", "id": 1})").find("missing field 'state'"), std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "state", "id": 1, "state": [1]})").find("must be an object"), std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "state", "id": 1.5, "state": {}})").find("must be an integer"), std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "state", "id": 1, "state": {}, "playback": "yes"})").find("'playback' must be true or false"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "state", "id": 1, "state": {}, "interactive": true, "playback": true})").find("cannot both"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "state", "id": 1, "state": {}, "interactive": 1})").find("true or false"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"type": "ping"})").find("ping: missing field 'id'"), std::string::npos);
}

TEST(ProtocolCodec, RejectsOversizedMessages)
{
    std::string big = R"({"type": "ping", "id": 1, "pad": ")" + std::string(kMaxClientMessageBytes, 'x') + "\"}";
    EXPECT_NE(errorOf(big).find("over the limit"), std::string::npos);
    // Just under the limit parses as far as the fields go.
    std::string fits = R"({"type": "cancel", "pad": ")" + std::string(1000, 'x') + "\"}";
    EXPECT_NE(errorOf(fits).find("unknown field 'pad'"), std::string::npos);
}

TEST(ProtocolCodec, ServerTextMessages)
{
    EXPECT_EQ(json::parse(helloReply("s1")), (json{{"type", "hello"}, {"protocol", 1}, {"session", "s1"}}));
    EXPECT_EQ(json::parse(pongReply(4)), (json{{"type", "pong"}, {"id", 4}}));
    const json e = json::parse(errorReply("bad thing", 12));
    EXPECT_EQ(e["type"], "error");
    EXPECT_EQ(e["message"], "bad thing");
    EXPECT_EQ(e["id"], 12);
    EXPECT_FALSE(json::parse(errorReply("x")).contains("id"));
    // Invalid UTF-8 quoted from client input must not throw.
    EXPECT_NO_THROW(EXPECT_TRUE(json::parse(errorReply("bad \xff\xfe input")).is_object()));
}

TEST(FrameEncoding, HeaderAloneIsReadWithoutTheRest)
{
    const std::vector<uint8_t> jpeg(1000, 7);
    const std::vector<float> depth(64, 1.0f);
    const std::string bytes = encodeFrame({{"type", "frame"}, {"id", 42}, {"converged", true}}, jpeg, depth, 8, 8);
    const json header = frameHeader(bytes);
    EXPECT_EQ(header["id"], 42);
    EXPECT_EQ(header, decodeFrame(bytes).header);
    EXPECT_THROW(frameHeader(bytes.substr(0, 3)), Error);
    EXPECT_THROW(frameHeader(bytes.substr(0, 10)), Error);
}

TEST(FrameEncoding, LayoutIsLengthHeaderJpegDepth)
{
    const std::vector<uint8_t> jpeg = {0xff, 0xd8, 0xff, 0xe0, 1, 2, 3, 0xff, 0xd9};
    const float inf = std::numeric_limits<float>::infinity();
    const std::vector<float> depth = {1.5f, inf, 3.25f, 6371.0f, 0.0f, -2.0f};
    const std::string bytes = encodeFrame({{"type", "frame"}, {"id", 3}}, jpeg, depth, 3, 2);

    // u32 little-endian header length.
    const uint32_t headerBytes = uint32_t(uint8_t(bytes[0])) | uint32_t(uint8_t(bytes[1])) << 8 |
                                 uint32_t(uint8_t(bytes[2])) << 16 | uint32_t(uint8_t(bytes[3])) << 24;
    ASSERT_EQ(bytes.size(), 4 + headerBytes + jpeg.size() + depth.size() * 4);
    const json header = json::parse(bytes.substr(4, headerBytes));
    EXPECT_EQ(header["type"], "frame");
    EXPECT_EQ(header["id"], 3);
    EXPECT_EQ(header["jpegBytes"], jpeg.size());
    EXPECT_EQ(header["depthWidth"], 3);
    EXPECT_EQ(header["depthHeight"], 2);
    EXPECT_EQ(header["depthBytes"], 24);
    EXPECT_EQ(std::memcmp(bytes.data() + 4 + headerBytes, jpeg.data(), jpeg.size()), 0);
    // Depth: float32 little-endian, row-major; 1.5f = 0x3fc00000, +inf = 0x7f800000.
    const size_t d = 4 + headerBytes + jpeg.size();
    EXPECT_EQ(uint8_t(bytes[d + 0]), 0x00);
    EXPECT_EQ(uint8_t(bytes[d + 2]), 0xc0);
    EXPECT_EQ(uint8_t(bytes[d + 3]), 0x3f);
    EXPECT_EQ(uint8_t(bytes[d + 6]), 0x80);
    EXPECT_EQ(uint8_t(bytes[d + 7]), 0x7f);

    const DecodedFrame f = decodeFrame(bytes);
    EXPECT_EQ(f.jpeg.size(), jpeg.size());
    ASSERT_EQ(f.depth.size(), depth.size());
    for (size_t i = 0; i < depth.size(); ++i)
        EXPECT_EQ(f.depth[i], depth[i]);
}

TEST(FrameEncoding, DecodeRejectsBadLayouts)
{
    const std::string good = encodeFrame({{"type", "frame"}}, std::vector<uint8_t>(5, 1), std::vector<float>(4, 1.0f), 2, 2);
    EXPECT_THROW(decodeFrame(good.substr(0, 3)), Error);
    EXPECT_THROW(decodeFrame(good.substr(0, good.size() - 1)), Error);
    EXPECT_THROW(decodeFrame(good + "x"), Error);
    std::string huge = good;
    huge[3] = char(0x7f);
    EXPECT_THROW(decodeFrame(huge), Error);
}

TEST(FrameEncoding, DepthDownsampleKeepsNearestFinite)
{
    const float inf = std::numeric_limits<float>::infinity();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    // 5 x 3 image, factor 2 -> 3 x 2 blocks (the last column and row are partial).
    const std::vector<float> depth = {
        9, 4, inf, inf, 7,   //
        8, 5, inf, nan, inf, //
        inf, inf, 2, 3, inf,
    };
    int w = 0, h = 0;
    const auto out = downsampleDepth(depth, 5, 3, 2, w, h);
    ASSERT_EQ(w, 3);
    ASSERT_EQ(h, 2);
    EXPECT_EQ(out[0], 4);
    EXPECT_EQ(out[1], inf);  // only inf and NaN in that block
    EXPECT_EQ(out[2], 7);
    EXPECT_EQ(out[3], inf);
    EXPECT_EQ(out[4], 2);
    EXPECT_EQ(out[5], inf);
}

}  // namespace
}  // namespace raypc::server
