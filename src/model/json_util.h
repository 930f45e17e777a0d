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
/// Appends `ch` to `out`, a control character escaped (\n, \r, \t, \xNN).
void append_escaped(std::string& out, unsigned char ch);
/// `text` with control characters escaped (\n, \t, \xNN), so that names taken from a file
/// (object keys, strings) cannot split an error message over several lines.
std::string one_line(std::string_view text);

Result<nlohmann::json> parse_json(std::string_view text, std::string_view source);
/// The whole file, refused past size_limits().input_bytes (256 MiB: a 1M-node tree is about
/// 100 MB; without a bound a path such as /dev/zero would be read until memory runs out). A
/// regular file is sized before it is read; with `regular_file_only` anything else (a device,
/// a FIFO) is refused before it is opened.
Result<std::string> read_text_file(const std::string& path, bool regular_file_only = false);
/// The rules for replacing an output file (docs/cli.md, "Outputs"): a symbolic link and
/// anything but a regular file (a directory, device, FIFO) are refused; the result is the mode
/// the written file gets, an existing file's own, else 0666 less the umask.
Result<uint32_t> output_file_mode(const std::string& path);
/// Creates a temporary file beside `path` (PATH.tmp-hmsm-XXXXXX, mode 0600) and opens it for
/// writing; its name goes into `temporary`. Returns the descriptor.
Result<int> create_temporary_beside(const std::string& path, std::string& temporary);
/// Writes to a temporary file beside `path`, then renames: no partial file on failure, an
/// existing file's mode kept, output_file_mode's refusals.
Status write_text_file_atomically(const std::string& path, std::string_view text);

class JsonReader {
public:
    JsonReader(std::string_view source, ErrorCode code) : source_(source), code_(code) {}

    Status expect_object(const nlohmann::json& j, const std::string& where) const;
    /// "format" equal to `format` and "version" an integer in [1, max_version] (to *version_out).
    Status expect_format(const nlohmann::json& doc, const char* format, int max_version = 1,
                         int* version_out = nullptr) const;
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
