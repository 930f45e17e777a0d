#include "json_util.h"

#include "input_limits.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <sys/stat.h>
#include <unistd.h>

namespace hmsm::detail {

namespace {

/// Nesting depth of a JSON text, ignoring brackets inside strings.
int nesting_depth(std::string_view text) {
    int depth = 0, deepest = 0;
    bool in_string = false, escaped = false;
    for (char ch : text) {
        if (in_string) {
            if (escaped) escaped = false;
            else if (ch == '\\') escaped = true;
            else if (ch == '"') in_string = false;
        } else if (ch == '"') {
            in_string = true;
        } else if (ch == '[' || ch == '{') {
            deepest = std::max(deepest, ++depth);
            if (deepest > kMaxJsonDepth) break;
        } else if (ch == ']' || ch == '}') {
            --depth;
        }
    }
    return deepest;
}

}  // namespace

void append_escaped(std::string& out, unsigned char ch) {
    if (ch == '\n') out += "\\n";
    else if (ch == '\r') out += "\\r";
    else if (ch == '\t') out += "\\t";
    else if (ch < 0x20 || ch == 0x7f) {
        char buf[8];
        std::snprintf(buf, sizeof buf, "\\x%02x", ch);
        out += buf;
    } else {
        out += char(ch);
    }
}

std::string one_line(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (unsigned char ch : text) append_escaped(out, ch);
    return out;
}

Result<nlohmann::json> parse_json(std::string_view text, std::string_view source) {
    if (text.find_first_not_of(" \t\r\n") == std::string_view::npos)
        return Status{ErrorCode::invalid_tree, std::string(source) + ": empty file, expected JSON"};
    if (nesting_depth(text) > kMaxJsonDepth)
        return Status{ErrorCode::invalid_tree, std::string(source) + ": JSON nested deeper than " +
                                                   std::to_string(kMaxJsonDepth) + " levels"};
    nlohmann::json doc = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
    if (doc.is_discarded()) {
        // Parse again with exceptions only to obtain the parser's position message.
        try {
            nlohmann::json unused = nlohmann::json::parse(text);
            (void)unused;
        } catch (const nlohmann::json::exception& e) {
            return Status{ErrorCode::invalid_tree,
                          one_line(std::string(source) + ": not valid JSON (" + quote_input(e.what()) + ")")};
        }
        return Status{ErrorCode::invalid_tree, std::string(source) + ": not valid JSON"};
    }
    return doc;
}

Result<std::string> read_text_file(const std::string& path, bool regular_file_only) {
    const uint64_t limit = size_limits().input_bytes;
    auto too_large = [&] {
        return Status{ErrorCode::io, one_line(path) + ": larger than " + std::to_string(limit >> 20) +
                                         " MiB, the limit of an input file (docs/model.md 3.11)"};
    };
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (std::filesystem::is_directory(status))
        return Status{ErrorCode::io, one_line(path) + ": is a directory, expected a file"};
    if (std::filesystem::is_regular_file(status)) {
        const auto size = std::filesystem::file_size(path, ec);
        if (!ec && size > limit) return too_large();
    } else if (regular_file_only && std::filesystem::exists(status)) {
        return Status{ErrorCode::io, one_line(path) + ": not a regular file (a device, FIFO or socket)"};
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) return Status{ErrorCode::io, one_line(path) + ": cannot open file for reading"};
    std::string text;
    char chunk[1 << 16];
    while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
        if (text.size() + uint64_t(in.gcount()) > limit) return too_large();
        text.append(chunk, size_t(in.gcount()));
    }
    if (in.bad()) return Status{ErrorCode::io, one_line(path) + ": read error"};
    return text;
}

Result<uint32_t> output_file_mode(const std::string& path) {
    struct stat existing {};
    if (::lstat(path.c_str(), &existing) != 0) {
        const mode_t mask = ::umask(0);
        ::umask(mask);
        return uint32_t(0666 & ~mask);
    }
    if (S_ISLNK(existing.st_mode))
        return Status{ErrorCode::io, one_line(path) + ": is a symbolic link; hmsm does not replace links, "
                                                       "name the file itself"};
    if (S_ISDIR(existing.st_mode)) return Status{ErrorCode::io, one_line(path) + ": is a directory"};
    if (!S_ISREG(existing.st_mode))
        return Status{ErrorCode::io, one_line(path) + ": is not a regular file (a device, FIFO or socket); "
                                                       "hmsm replaces only regular files"};
    return uint32_t(existing.st_mode & 07777);
}

Result<int> create_temporary_beside(const std::string& path, std::string& temporary) {
    std::string name = path + ".tmp-hmsm-XXXXXX";
    const int fd = ::mkstemp(name.data());
    if (fd < 0) return Status{ErrorCode::io, one_line(path) + ": cannot open for writing"};
    temporary = name;
    return fd;
}

Status write_text_file_atomically(const std::string& path, std::string_view text) {
    auto mode = output_file_mode(path);
    if (!mode) return mode.status();
    std::string temporary;
    auto fd = create_temporary_beside(path, temporary);
    if (!fd) return fd.status();
    std::FILE* out = ::fdopen(*fd, "wb");
    if (!out) {
        ::close(*fd);
        std::remove(temporary.c_str());
        return {ErrorCode::io, one_line(path) + ": cannot open file for writing"};
    }
    const bool written = std::fwrite(text.data(), 1, text.size(), out) == text.size() &&
                         ::fchmod(*fd, mode_t(*mode)) == 0;
    if (std::fclose(out) != 0 || !written) {
        std::remove(temporary.c_str());
        return {ErrorCode::io, one_line(path) + ": write error"};
    }
    std::error_code ec;
    std::filesystem::rename(temporary, path, ec);
    if (ec) {
        std::remove(temporary.c_str());
        return {ErrorCode::io, one_line(path) + ": cannot write file (" + ec.message() + ")"};
    }
    return {};
}

Status JsonReader::error(const std::string& where, const char* key, const std::string& what) const {
    std::string item = where.empty() ? std::string(key) : where + "." + key;
    return {code_, one_line(source_ + ": " + item + ": " + what)};
}

const nlohmann::json* JsonReader::field(const nlohmann::json& obj, const char* key) const {
    auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
}

Status JsonReader::expect_object(const nlohmann::json& j, const std::string& where) const {
    if (!j.is_object())
        return {code_, source_ + ": " + (where.empty() ? std::string("document") : where) +
                           ": expected a JSON object"};
    return {};
}

Status JsonReader::expect_format(const nlohmann::json& doc, const char* format, int max_version,
                                 int* version_out) const {
    std::string value;
    HMSM_TRY(string_field(doc, "", "format", value));
    if (value != format)
        return error("", "format", "is \"" + quote_input(value) + "\", expected \"" + format + "\"");
    const auto* version = field(doc, "version");
    if (!version) return error("", "version", "missing");
    if (!version->is_number_integer() || version->get<int64_t>() < 1 || version->get<int64_t>() > max_version)
        return error("", "version", "is " + quote_input(version->dump()) +
                                        (max_version == 1 ? std::string(", only version 1 is supported")
                                                          : ", only versions 1 to " + std::to_string(max_version) +
                                                                " are supported"));
    if (version_out) *version_out = int(version->get<int64_t>());
    return {};
}

Status JsonReader::array_field(const nlohmann::json& obj, const std::string& where,
                               const char* key, const nlohmann::json*& out) const {
    out = field(obj, key);
    if (!out) return error(where, key, "missing");
    if (!out->is_array()) return error(where, key, "expected an array");
    return {};
}

Status JsonReader::string_field(const nlohmann::json& obj, const std::string& where,
                                const char* key, std::string& out) const {
    const auto* f = field(obj, key);
    if (!f) return error(where, key, "missing");
    if (!f->is_string()) return error(where, key, "expected a string");
    out = f->get<std::string>();
    return {};
}

Status JsonReader::int_field(const nlohmann::json& obj, const std::string& where, const char* key,
                             int32_t& out) const {
    const auto* f = field(obj, key);
    if (!f) return error(where, key, "missing");
    if (!f->is_number_integer()) return error(where, key, "expected an integer, got " + quote_input(f->dump()));
    int64_t v = f->get<int64_t>();
    if (f->is_number_unsigned() && f->get<uint64_t>() > uint64_t(INT32_MAX))
        return error(where, key, "integer " + quote_input(f->dump()) + " out of range");
    if (v < INT32_MIN || v > INT32_MAX) return error(where, key, "integer " + quote_input(f->dump()) + " out of range");
    out = int32_t(v);
    return {};
}

Status JsonReader::number_field(const nlohmann::json& obj, const std::string& where,
                                const char* key, double& out) const {
    const auto* f = field(obj, key);
    if (!f) return error(where, key, "missing");
    if (!f->is_number()) return error(where, key, "expected a number, got " + quote_input(f->dump()));
    out = f->get<double>();
    if (!std::isfinite(out)) return error(where, key, "number is not finite");
    return {};
}

Status JsonReader::vec3_field(const nlohmann::json& obj, const std::string& where,
                              const char* key, glm::dvec3& out) const {
    const auto* f = field(obj, key);
    if (!f) return error(where, key, "missing");
    if (!f->is_array() || f->size() != 3) return error(where, key, "expected an array of 3 numbers");
    for (int k = 0; k < 3; ++k) {
        const auto& v = (*f)[k];
        if (!v.is_number()) return error(where, key, "expected an array of 3 numbers");
        out[k] = v.get<double>();
        if (!std::isfinite(out[k])) return error(where, key, "number is not finite");
    }
    return {};
}

Status JsonReader::vec2_field(const nlohmann::json& obj, const std::string& where,
                              const char* key, glm::dvec2& out) const {
    const auto* f = field(obj, key);
    if (!f) return error(where, key, "missing");
    if (!f->is_array() || f->size() != 2) return error(where, key, "expected an array of 2 numbers");
    for (int k = 0; k < 2; ++k) {
        const auto& v = (*f)[k];
        if (!v.is_number()) return error(where, key, "expected an array of 2 numbers");
        out[k] = v.get<double>();
        if (!std::isfinite(out[k])) return error(where, key, "number is not finite");
    }
    return {};
}

}  // namespace hmsm::detail
