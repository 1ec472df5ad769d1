// The materials table of a volume: id 0 is "empty" (reserved); ids 1..65535 are user materials.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

using MaterialId = uint16_t;
constexpr MaterialId kEmptyMaterial = 0;
constexpr std::size_t kMaxMaterials = 65535; // user materials, ids 1..65535

struct Material {
    std::string name;
    std::array<float, 4> color{0.8f, 0.8f, 0.8f, 1.0f}; // linear RGBA in [0,1]
    float toughness = 0.5f;                              // 0 = soft (erodes fully), 1 = unerodable
    /// Optional: a picture (PNG, JPEG, ...) the renderer maps tri-planarly over the material, tinted by
    /// its colour. A relative path is taken from the scene file's folder.
    std::string texture;
};
constexpr std::size_t kMaxTexturePathBytes = 4096;

class MaterialTable {
public:
    /// A new table holds one material, "default" (id 1).
    MaterialTable();

    /// Number of user materials (ids 1..size()).
    std::size_t size() const { return materials_.size(); }
    const Material& at(MaterialId id) const; // throws std::out_of_range for 0 or unknown ids
    std::optional<MaterialId> find(const std::string& name) const;

    /// Adds a material, or updates colour, toughness and texture of the one with the same name. Returns its id.
    /// Throws std::invalid_argument on an empty name, out-of-range values or a full table.
    MaterialId define(const Material& material);

    std::vector<std::string> names() const;

    std::string toJson() const;
    /// Throws std::runtime_error with a clear message on malformed input.
    static MaterialTable fromJson(const std::string& json);

    friend bool operator==(const MaterialTable& a, const MaterialTable& b);

private:
    std::vector<Material> materials_; // materials_[id - 1]
};

} // namespace vdbclay
