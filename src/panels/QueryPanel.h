// The query panel ("Find models"): searches a model library with the sculpture as the view shows it,
// whole or within a box, lists the nearest models with their thumbnails and distances, and places a
// chosen one at the brush as one undoable edit. The search and the placing's voxelization run on their
// own thread (ModelSearch); the frame only starts them and shows what they left.
#pragma once

#include "editor/ModelSearch.h"
#include "editor/SessionWorker.h"
#include "panels/FileBrowser.h"

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

class QueryPanel {
public:
    /// Draws the panel's widgets into the window being built; appends the commands it issued (a
    /// placement's op) to `out` and its outcomes to `status`; records its buttons' rectangles in `rects`
    /// ("Search", "Place 1", "Place 2", ...). `brushPoint`: where the brush is (the last surface point under
    /// the pointer, a hand's brush), for placing.
    void draw(SessionWorker& session, const std::optional<std::array<double, 3>>& brushPoint, std::vector<Command>& out, std::string& status,
              std::map<std::string, std::array<float, 4>>& rects);
    /// The browser's window, when it is open (drawn after the panels' windows).
    void drawBrowser();

    std::string library;  // the library file searched
    bool useBox = false;  // search with the part of the sculpture inside the box only
    float boxMin[3] = {-8, -8, -8}, boxMax[3] = {8, 8, 8};
    int descriptor = 0;   // kDescriptors' index: combined, clusterd2, d2, lightfield
    /// Searches draw the sculpture's silhouettes too (ModelSearchRequest::lightField): the front ends
    /// with a renderer set it; headless sessions and tests leave it off.
    bool lightField = false;
    int count = 8;        // models listed

    /// What the last search found (the panel lists it).
    const std::vector<ModelSearchResult>& results() const { return results_; }
    /// The search's thread: tests wait for it.
    ModelSearch& search() { return search_; }

private:
    /// A thumbnail as ImGui draws it without a texture: colour cells, runs of one colour merged.
    struct Cells {
        int side = 0;
        std::vector<uint32_t> colours; // ImGui colours (IM_COL32), side x side, rows from the top
    };
    void drawThumbnail(const Cells& cells, float size) const;

    ModelSearch search_;
    std::vector<ModelSearchResult> results_;
    std::vector<Cells> thumbnails_;
    FileBrowser browser_;
};

} // namespace vdbclay
