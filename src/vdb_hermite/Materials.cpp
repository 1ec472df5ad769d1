#include "vdb_hermite/Materials.h"

#include "vdb_hermite/PrintableText.h"

#include <nlohmann/json.hpp>

#include <stdexcept>

namespace vdbclay {

namespace {

void validate(const Material& m)
{
    if (m.name.empty()) throw std::invalid_argument("a material needs a non-empty name");
    if (!isPrintableName(m.name))
        throw std::invalid_argument("the material name '" + printableText(m.name, 80) +
                                    "' is not printable text: names are UTF-8 of at most 256 bytes without control characters");
    for (float c : m.color) {
        if (!(c >= 0.0f && c <= 1.0f))
            throw std::invalid_argument("material '" + m.name + "': colour components must lie in [0,1]");
    }
    if (!(m.toughness >= 0.0f && m.toughness <= 1.0f))
        throw std::invalid_argument("material '" + m.name + "': toughness must lie in [0,1]");
    if (!isPrintableName(m.texture, kMaxTexturePathBytes))
        throw std::invalid_argument("material '" + m.name + "': the texture path '" + printableText(m.texture, 80) +
                                    "' is not printable text of at most 4096 bytes");
}

} // namespace

MaterialTable::MaterialTable() { materials_.push_back(Material{"default", {0.8f, 0.8f, 0.8f, 1.0f}, 0.5f, {}}); }

const Material& MaterialTable::at(MaterialId id) const
{
    if (id == kEmptyMaterial || id > materials_.size())
        throw std::out_of_range("unknown material id " + std::to_string(id));
    return materials_[id - 1];
}

std::optional<MaterialId> MaterialTable::find(const std::string& name) const
{
    for (std::size_t i = 0; i < materials_.size(); ++i) {
        if (materials_[i].name == name) return MaterialId(i + 1);
    }
    return std::nullopt;
}

MaterialId MaterialTable::define(const Material& material)
{
    validate(material);
    if (auto id = find(material.name)) {
        materials_[*id - 1] = material;
        return *id;
    }
    if (materials_.size() >= kMaxMaterials) throw std::invalid_argument("the materials table is full (65535)");
    materials_.push_back(material);
    return MaterialId(materials_.size());
}

std::vector<std::string> MaterialTable::names() const
{
    std::vector<std::string> out;
    out.reserve(materials_.size());
    for (const auto& m : materials_) out.push_back(m.name);
    return out;
}

std::string MaterialTable::toJson() const
{
    nlohmann::json arr = nlohmann::json::array();
    for (const auto& m : materials_) {
        nlohmann::json item{{"name", m.name}, {"color", m.color}, {"toughness", m.toughness}};
        if (!m.texture.empty()) item["texture"] = m.texture; // tables without textures read as before
        arr.push_back(std::move(item));
    }
    return arr.dump();
}

MaterialTable MaterialTable::fromJson(const std::string& text)
{
    nlohmann::json arr;
    try {
        arr = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(std::string("materials table is not valid JSON: ") + e.what());
    }
    if (!arr.is_array() || arr.empty()) throw std::runtime_error("materials table must be a non-empty JSON array");
    if (arr.size() > kMaxMaterials) throw std::runtime_error("materials table holds more than 65535 materials");
    MaterialTable table;
    table.materials_.clear();
    try {
        for (const auto& item : arr) {
            Material m;
            m.name = item.at("name").get<std::string>();
            m.color = item.at("color").get<std::array<float, 4>>();
            m.toughness = item.at("toughness").get<float>();
            if (item.contains("texture")) m.texture = item.at("texture").get<std::string>();
            validate(m);
            if (table.find(m.name)) throw std::runtime_error("duplicate material name '" + m.name + "'");
            table.materials_.push_back(m);
        }
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(std::string("malformed materials table: ") + e.what());
    } catch (const std::invalid_argument& e) {
        throw std::runtime_error(std::string("malformed materials table: ") + e.what());
    }
    return table;
}

bool operator==(const MaterialTable& a, const MaterialTable& b)
{
    if (a.materials_.size() != b.materials_.size()) return false;
    for (std::size_t i = 0; i < a.materials_.size(); ++i) {
        const auto& x = a.materials_[i];
        const auto& y = b.materials_[i];
        if (x.name != y.name || x.color != y.color || x.toughness != y.toughness || x.texture != y.texture) return false;
    }
    return true;
}

} // namespace vdbclay
