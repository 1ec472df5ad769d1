#include "voxelize/PlyStrips.h"

#include "vdb_hermite/PrintableText.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

namespace vdbclay {

namespace {

enum class PlyFormat { Ascii, LittleEndian, BigEndian };

struct PlyProperty {
    std::string name;
    int bytes = 0;             // of the value (of each entry, for a list)
    bool isFloat = false, isSigned = false;
    int countBytes = 0;        // a list: bytes of its count; 0: a scalar
    bool countSigned = false;
};

struct PlyElementSpec {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

/// A type's size and kind; false for a name PLY does not define.
bool plyType(const std::string& name, int& bytes, bool& isFloat, bool& isSigned)
{
    static const struct {
        const char* a;
        const char* b;
        int bytes;
        bool isFloat, isSigned;
    } kTypes[] = {{"char", "int8", 1, false, true},    {"uchar", "uint8", 1, false, false}, {"short", "int16", 2, false, true},
                  {"ushort", "uint16", 2, false, false}, {"int", "int32", 4, false, true},    {"uint", "uint32", 4, false, false},
                  {"float", "float32", 4, true, true},   {"double", "float64", 8, true, true}};
    for (const auto& t : kTypes)
        if (name == t.a || name == t.b) {
            bytes = t.bytes;
            isFloat = t.isFloat;
            isSigned = t.isSigned;
            return true;
        }
    return false;
}

/// Reads the body's values one at a time, in the file's own form.
class PlyValues {
public:
    PlyValues(const std::string& path, std::string body, PlyFormat format) : path_(path), body_(std::move(body)), format_(format)
    {
        if (format_ == PlyFormat::Ascii) text_.str(body_);
    }

    double next(int bytes, bool isFloat, bool isSigned)
    {
        if (format_ == PlyFormat::Ascii) {
            double v = 0.0;
            if (!(text_ >> v)) fail("its values end early or are not numbers");
            return v;
        }
        if (at_ + std::size_t(bytes) > body_.size()) fail("its values end early");
        unsigned char raw[8];
        std::memcpy(raw, body_.data() + at_, std::size_t(bytes));
        at_ += std::size_t(bytes);
        if (format_ == PlyFormat::BigEndian) std::reverse(raw, raw + bytes);
        if (isFloat) {
            if (bytes == 4) {
                float f;
                std::memcpy(&f, raw, 4);
                return f;
            }
            double d;
            std::memcpy(&d, raw, 8);
            return d;
        }
        uint64_t u = 0;
        for (int i = bytes - 1; i >= 0; --i) u = (u << 8) | raw[i];
        if (isSigned && bytes < 8 && (u >> (8 * bytes - 1)) & 1u) return double(int64_t(u | (~uint64_t(0) << (8 * bytes))));
        return double(u);
    }

    [[noreturn]] void fail(const std::string& why) const { throw MeshImportError("'" + path_ + "' is a damaged PLY file: " + why); }

private:
    std::string path_, body_;
    PlyFormat format_;
    std::size_t at_ = 0;
    std::istringstream text_;
};

/// Appends triangle (a, b, c) unless two corners are the same vertex (a strip's stitching triangles);
/// one of zero area or with a corner out of range counts as dropped, as the Assimp reader counts them.
void addTriangle(TriangleSoup& soup, int64_t a, int64_t b, int64_t c, std::size_t vertices)
{
    if (a == b || b == c || a == c) return;
    if (a < 0 || b < 0 || c < 0 || uint64_t(a) >= vertices || uint64_t(b) >= vertices || uint64_t(c) >= vertices) {
        ++soup.droppedTriangles;
        return;
    }
    const auto& p = soup.positions[std::size_t(a)];
    const auto& q = soup.positions[std::size_t(b)];
    const auto& r = soup.positions[std::size_t(c)];
    const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    const double area2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (!std::isfinite(area2) || !(area2 > 0.0)) {
        ++soup.droppedTriangles;
        return;
    }
    soup.triangles.push_back({uint32_t(a), uint32_t(b), uint32_t(c)});
    soup.triangleMaterials.push_back(0);
}

} // namespace

std::optional<TriangleSoup> readPlyTriangleStrips(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    std::string line;
    if (!std::getline(in, line) || line.rfind("ply", 0) != 0) return std::nullopt;
    PlyFormat format = PlyFormat::Ascii;
    std::vector<PlyElementSpec> elements;
    bool strips = false, ended = false;
    while (!ended && std::getline(in, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::istringstream words(line);
        std::string keyword;
        words >> keyword;
        if (keyword == "end_header") {
            ended = true;
        } else if (keyword == "format") {
            std::string form;
            words >> form;
            format = form == "binary_little_endian" ? PlyFormat::LittleEndian : form == "binary_big_endian" ? PlyFormat::BigEndian : PlyFormat::Ascii;
        } else if (keyword == "element") {
            PlyElementSpec e;
            words >> e.name >> e.count;
            strips = strips || (e.name == "tristrips" && e.count > 0);
            elements.push_back(e);
        } else if (keyword == "property" && !elements.empty()) {
            PlyProperty p;
            std::string type;
            words >> type;
            if (type == "list") {
                std::string countType;
                words >> countType >> type;
                int bytes = 0;
                bool isFloat = false;
                if (!plyType(countType, bytes, isFloat, p.countSigned) || isFloat) return std::nullopt; // Assimp says what is wrong
                p.countBytes = bytes;
            }
            if (!plyType(type, p.bytes, p.isFloat, p.isSigned)) return std::nullopt;
            words >> p.name;
            elements.back().properties.push_back(p);
        }
    }
    if (!ended || !strips) return std::nullopt;
    PlyValues values(path, std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()), format);

    TriangleSoup soup;
    soup.materials.push_back({});
    bool sawVertices = false;
    for (const PlyElementSpec& e : elements) {
        const bool vertex = e.name == "vertex", face = e.name == "face", strip = e.name == "tristrips";
        int axis[3] = {-1, -1, -1};
        for (std::size_t k = 0; k < e.properties.size(); ++k)
            for (int a = 0; a < 3; ++a)
                if (e.properties[k].name == std::string(1, char('x' + a)) && e.properties[k].countBytes == 0) axis[a] = int(k);
        if (vertex) {
            if (axis[0] < 0 || axis[1] < 0 || axis[2] < 0) values.fail("its vertices have no x, y and z");
            sawVertices = true;
        }
        if (e.properties.empty()) continue; // nothing to read, however many it claims
        for (uint64_t i = 0; i < e.count; ++i) {
            std::array<double, 3> position{};
            for (std::size_t k = 0; k < e.properties.size(); ++k) {
                const PlyProperty& p = e.properties[k];
                if (p.countBytes == 0) {
                    const double v = values.next(p.bytes, p.isFloat, p.isSigned);
                    for (int a = 0; a < 3; ++a)
                        if (int(k) == axis[a]) position[std::size_t(a)] = v;
                    continue;
                }
                const double n = values.next(p.countBytes, false, p.countSigned);
                if (!(n >= 0.0 && n <= 1e9)) values.fail("a list of " + std::to_string(n) + " entries");
                const bool indices = (face || strip) && (p.name == "vertex_indices" || p.name == "vertex_index");
                std::vector<int64_t> list;
                for (uint64_t j = 0; j < uint64_t(n); ++j) {
                    const double v = values.next(p.bytes, p.isFloat, p.isSigned);
                    if (!indices) continue;
                    if (!(std::fabs(v) <= 4e9)) values.fail("a vertex index of " + std::to_string(v));
                    list.push_back(int64_t(v));
                }
                if (!indices) continue;
                if (face) // a polygon: a fan from its first corner
                    for (std::size_t j = 2; j < list.size(); ++j) addTriangle(soup, list[0], list[j - 1], list[j], soup.positions.size());
                if (strip) { // -1 restarts the strip; every other triangle turns the other way, to keep one winding
                    std::size_t start = 0;
                    for (std::size_t j = 0; j < list.size(); ++j) {
                        if (list[j] < 0) {
                            start = j + 1;
                            continue;
                        }
                        if (j < start + 2) continue;
                        if ((j - start) % 2 == 0) addTriangle(soup, list[j - 2], list[j - 1], list[j], soup.positions.size());
                        else addTriangle(soup, list[j - 1], list[j - 2], list[j], soup.positions.size());
                    }
                }
            }
            if (vertex) soup.positions.push_back(position);
        }
    }
    if (!sawVertices) values.fail("it has no vertex element");
    if (soup.triangles.empty()) throw MeshImportError("'" + path + "' holds no triangle");
    return soup;
}

} // namespace vdbclay
