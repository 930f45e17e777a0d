#include "json_util.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

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

std::string one_line(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (unsigned char ch : text) {
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
                          one_line(std::string(source) + ": not valid JSON (" + e.what() + ")")};
        }
        return Status{ErrorCode::invalid_tree, std::string(source) + ": not valid JSON"};
    }
    return doc;
}

Result<std::string> read_text_file(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        return Status{ErrorCode::io, path + ": is a directory, expected a file"};
    std::ifstream in(path, std::ios::binary);
    if (!in) return Status{ErrorCode::io, path + ": cannot open file for reading"};
    std::string text;
    char chunk[1 << 16];
    while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
        text.append(chunk, size_t(in.gcount()));
        if (text.size() > kMaxTextFileBytes)
            return Status{ErrorCode::io, one_line(path + ": larger than " +
                                                  std::to_string(kMaxTextFileBytes >> 20) +
                                                  " MiB, not a tree or forest file")};
    }
    if (in.bad()) return Status{ErrorCode::io, path + ": read error"};
    return text;
}

Status write_text_file_atomically(const std::string& path, std::string_view text) {
    std::string temporary = path + ".tmp-hmsm";
    {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        if (!out) return {ErrorCode::io, path + ": cannot open file for writing"};
        out.write(text.data(), std::streamsize(text.size()));
        out.close();
        if (!out) {
            std::remove(temporary.c_str());
            return {ErrorCode::io, path + ": write error"};
        }
    }
    std::error_code ec;
    std::filesystem::rename(temporary, path, ec);
    if (ec) {
        std::remove(temporary.c_str());
        return {ErrorCode::io, path + ": cannot write file (" + ec.message() + ")"};
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

Status JsonReader::expect_format(const nlohmann::json& doc, const char* format) const {
    std::string value;
    HMSM_TRY(string_field(doc, "", "format", value));
    if (value != format)
        return error("", "format", "is \"" + value + "\", expected \"" + format + "\"");
    const auto* version = field(doc, "version");
    if (!version) return error("", "version", "missing");
    if (!version->is_number_integer() || version->get<int64_t>() != 1)
        return error("", "version", "is " + version->dump() + ", only version 1 is supported");
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
    if (!f->is_number_integer()) return error(where, key, "expected an integer, got " + f->dump());
    int64_t v = f->get<int64_t>();
    if (f->is_number_unsigned() && f->get<uint64_t>() > uint64_t(INT32_MAX))
        return error(where, key, "integer " + f->dump() + " out of range");
    if (v < INT32_MIN || v > INT32_MAX) return error(where, key, "integer " + f->dump() + " out of range");
    out = int32_t(v);
    return {};
}

Status JsonReader::number_field(const nlohmann::json& obj, const std::string& where,
                                const char* key, double& out) const {
    const auto* f = field(obj, key);
    if (!f) return error(where, key, "missing");
    if (!f->is_number()) return error(where, key, "expected a number, got " + f->dump());
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
