// Strict JSON field access with messages that name the file, the item and the field.
#pragma once

#include <hmsm/status.h>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <string_view>

namespace hmsm::detail {

/// Deepest nesting accepted; deeper documents are rejected before parsing.
inline constexpr int kMaxJsonDepth = 64;
/// Largest file read_text_file accepts (a 1M-node tree is ~100 MB): without a bound, a path such
/// as /dev/zero would be read until memory runs out.
inline constexpr uint64_t kMaxTextFileBytes = uint64_t(256) << 20;

/// `text` with control characters escaped (\n, \t, \xNN), so that names taken from a file
/// (object keys, strings) cannot split an error message over several lines.
std::string one_line(std::string_view text);

Result<nlohmann::json> parse_json(std::string_view text, std::string_view source);
Result<std::string> read_text_file(const std::string& path);
/// Writes to a temporary file beside `path`, then renames: no partial file on failure.
Status write_text_file_atomically(const std::string& path, std::string_view text);

class JsonReader {
public:
    JsonReader(std::string_view source, ErrorCode code) : source_(source), code_(code) {}

    Status expect_object(const nlohmann::json& j, const std::string& where) const;
    /// "format" equal to `format` and "version" equal to 1.
    Status expect_format(const nlohmann::json& doc, const char* format) const;
    Status array_field(const nlohmann::json& obj, const std::string& where, const char* key,
                       const nlohmann::json*& out) const;
    Status string_field(const nlohmann::json& obj, const std::string& where, const char* key,
                        std::string& out) const;
    Status int_field(const nlohmann::json& obj, const std::string& where, const char* key,
                     int32_t& out) const;
    Status number_field(const nlohmann::json& obj, const std::string& where, const char* key,
                        double& out) const;
    Status vec3_field(const nlohmann::json& obj, const std::string& where, const char* key,
                      glm::dvec3& out) const;
    Status vec2_field(const nlohmann::json& obj, const std::string& where, const char* key,
                      glm::dvec2& out) const;

    Status error(const std::string& where, const char* key, const std::string& what) const;

private:
    const nlohmann::json* field(const nlohmann::json& obj, const char* key) const;
    std::string source_;
    ErrorCode code_;
};

}  // namespace hmsm::detail
