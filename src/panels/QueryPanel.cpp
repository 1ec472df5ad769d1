#include "panels/QueryPanel.h"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <filesystem>

namespace vdbclay {

namespace {

constexpr const char* kDescriptorLabels[] = {"combined", "clusterd2", "d2", "lightfield"};
constexpr query::Descriptor kDescriptors[] = {query::Descriptor::Combined, query::Descriptor::ClusterD2, query::Descriptor::D2,
                                              query::Descriptor::LightField};
constexpr const char* kLibraryTitle = "Choose a model library";
/// Thumbnails are drawn as this many cells a side (ImGui 1.86's Vulkan backend draws one texture, its
/// font's: a picture is coloured rectangles, a few hundred after merging runs).
constexpr int kCells = 32;

} // namespace

void QueryPanel::draw(SessionWorker& session, const std::optional<std::array<double, 3>>& brushPoint, std::vector<Command>& out,
                      std::string& status, std::map<std::string, std::array<float, 4>>& rects)
{
    const auto track = [&](const std::string& label) {
        const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
        rects[label] = {lo.x, lo.y, hi.x, hi.y};
    };
    // What a finished job left.
    if (std::optional<ModelSearchOutcome> done = search_.take()) {
        if (!done->error.empty()) {
            status = "find models: " + done->error;
        } else if (done->results) {
            results_ = std::move(*done->results);
            thumbnails_.clear();
            for (const ModelSearchResult& r : results_) {
                Cells cells;
                if (r.thumbnail.width > 0 && r.thumbnail.height > 0) {
                    cells.side = kCells;
                    for (int y = 0; y < kCells; ++y)
                        for (int x = 0; x < kCells; ++x) {
                            // The mean of the pixels the cell covers.
                            const int x0 = x * r.thumbnail.width / kCells, x1 = std::max(x0 + 1, (x + 1) * r.thumbnail.width / kCells);
                            const int y0 = y * r.thumbnail.height / kCells, y1 = std::max(y0 + 1, (y + 1) * r.thumbnail.height / kCells);
                            unsigned sum[3] = {0, 0, 0}, n = 0;
                            for (int py = y0; py < y1; ++py)
                                for (int px = x0; px < x1; ++px, ++n)
                                    for (int c = 0; c < 3; ++c) sum[c] += r.thumbnail.pixel(px, py)[c];
                            cells.colours.push_back(IM_COL32(sum[0] / n, sum[1] / n, sum[2] / n, 255));
                        }
                }
                thumbnails_.push_back(std::move(cells));
            }
            status = results_.empty() ? "find models: the library is empty" : "found " + std::to_string(results_.size()) + " models";
            if (!done->note.empty()) status += "; " + done->note;
        } else if (done->placement) {
            Command c;
            c.kind = Command::Kind::ApplyOp;
            c.op = *done->placement;
            out.push_back(c);
            status = "placed the model at the brush (Ctrl+Z takes it back)";
        }
    }

    ImGui::InputText("Library", &library);
    ImGui::SameLine();
    if (ImGui::Button("...##library"))
        browser_.open(kLibraryTitle, std::filesystem::absolute(session.scenePath()).parent_path().string(), {".vdblib"}, false);
    // The light field is offered where the front end lets the search draw silhouettes.
    const int rankings = IM_ARRAYSIZE(kDescriptorLabels) - (lightField ? 0 : 1);
    descriptor = std::clamp(descriptor, 0, rankings - 1);
    ImGui::Combo("Ranking", &descriptor, kDescriptorLabels, rankings);
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(lightField ? "combined: ClusterD2+Color, D2 and the light field together" : "combined: ClusterD2+Color and D2 together");
    ImGui::SliderInt("Models", &count, 1, 32);
    ImGui::Checkbox("Only inside the box", &useBox);
    if (useBox) {
        ImGui::InputFloat3("Box min", boxMin);
        ImGui::InputFloat3("Box max", boxMax);
    }
    const bool busy = search_.busy();
    if (busy) ImGui::BeginDisabled();
    const bool start = ImGui::Button(busy ? "Searching..." : "Search");
    track("Search");
    if (busy) ImGui::EndDisabled();
    if (start) {
        ModelSearchRequest request;
        request.library = library;
        if (useBox) request.box = WorldBounds{Vec3d(boxMin[0], boxMin[1], boxMin[2]), Vec3d(boxMax[0], boxMax[1], boxMax[2])};
        request.descriptor = kDescriptors[descriptor];
        request.k = std::size_t(std::max(1, count));
        request.lightField = lightField;
        if (library.empty()) status = "find models: choose a library first (vdbclay index add makes one)";
        else search_.search(session.session(), request);
    }

    const float size = 64.0f;
    for (std::size_t i = 0; i < results_.size(); ++i) {
        ImGui::PushID(int(i));
        drawThumbnail(thumbnails_[i], size);
        ImGui::SameLine();
        ImGui::BeginGroup();
        const ModelSearchResult& r = results_[i];
        ImGui::Text("%zu. %s", i + 1, r.model.name.c_str());
        ImGui::TextDisabled("%s  distance %.4f", r.model.label.empty() ? "-" : r.model.label.c_str(), r.distance);
        const bool canPlace = brushPoint.has_value() && !busy;
        if (!canPlace) ImGui::BeginDisabled();
        const bool place = ImGui::Button("Place at the brush");
        track("Place " + std::to_string(i + 1));
        if (!canPlace) ImGui::EndDisabled();
        if (place && brushPoint) {
            const BrushSettings& brush = session.brush();
            search_.place(session.session(), r.model.path, *brushPoint, brush.radius, brush.material);
            status = "placing " + r.model.name + " ...";
        }
        ImGui::EndGroup();
        ImGui::PopID();
    }
}

void QueryPanel::drawBrowser()
{
    if (const auto chosen = browser_.draw()) library = *chosen;
}

void QueryPanel::drawThumbnail(const Cells& cells, float size) const
{
    const ImVec2 at = ImGui::GetCursorScreenPos();
    ImGui::Dummy(ImVec2(size, size));
    ImDrawList* list = ImGui::GetWindowDrawList();
    if (cells.side == 0) {
        list->AddRect(at, ImVec2(at.x + size, at.y + size), IM_COL32(128, 128, 128, 255));
        return;
    }
    const float cell = size / float(cells.side);
    for (int y = 0; y < cells.side; ++y)
        for (int x = 0; x < cells.side;) {
            const ImU32 colour = cells.colours[std::size_t(y * cells.side + x)];
            int end = x + 1;
            while (end < cells.side && cells.colours[std::size_t(y * cells.side + end)] == colour) ++end;
            list->AddRectFilled(ImVec2(at.x + float(x) * cell, at.y + float(y) * cell), ImVec2(at.x + float(end) * cell, at.y + float(y + 1) * cell), colour);
            x = end;
        }
}

} // namespace vdbclay
