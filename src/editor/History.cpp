#include "editor/History.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace vdbclay {

namespace {

uint64_t bytesOf(const std::vector<LeafChange>& changes)
{
    uint64_t n = 0;
    for (const LeafChange& c : changes) n += sizeof(LeafChange) + c.before.size() + c.after.size();
    return n;
}

void put(std::string& out, const void* data, std::size_t size) { out.append(static_cast<const char*>(data), size); }

void putString(std::string& out, const std::string& s)
{
    const uint64_t n = s.size();
    put(out, &n, sizeof n);
    out += s;
}

struct Reader {
    const std::string& in;
    std::size_t at = 0;
    void get(void* data, std::size_t size)
    {
        if (in.size() - at < size) throw std::runtime_error("the undo history's spill file is damaged");
        std::memcpy(data, in.data() + at, size);
        at += size;
    }
    std::string getString()
    {
        uint64_t n = 0;
        get(&n, sizeof n);
        if (in.size() - at < n) throw std::runtime_error("the undo history's spill file is damaged");
        std::string s = in.substr(at, std::size_t(n));
        at += std::size_t(n);
        return s;
    }
};

std::vector<LeafImage> imagesOf(const std::vector<LeafChange>& changes, bool before)
{
    std::vector<LeafImage> out;
    out.reserve(changes.size());
    for (const LeafChange& c : changes) out.push_back({c.origin, before ? c.before : c.after});
    return out;
}

} // namespace

History::History(const HistoryLimits& limits) : limits_(limits) {}

History::~History()
{
    if (spill_) std::fclose(spill_);
}

void History::push(std::vector<LeafChange> changes, nlohmann::json ops, std::optional<MaskChange> mask)
{
    changes.erase(std::remove_if(changes.begin(), changes.end(), [](const LeafChange& c) { return c.before == c.after; }), changes.end());
    if (mask && mask->before == mask->after) mask.reset();
    if (changes.empty() && !mask) return;
    for (Entry& e : redo_) release(e);
    redo_.clear();
    Entry entry;
    entry.bytes = bytesOf(changes);
    entry.changes = std::move(changes);
    entry.ops = std::move(ops);
    entry.mask = std::move(mask);
    memoryBytes_ += entry.bytes;
    undo_.push_back(std::move(entry));
    if (undo_.size() == 1 && redo_.empty() && spill_) { // nothing spilled is referenced any more
        std::fclose(spill_);
        spill_ = nullptr;
        fileEnd_ = spilledBytes_ = 0;
    }
    spillOver();
}

nlohmann::json History::opsInEffect() const
{
    nlohmann::json ops = forgottenOps_;
    for (const Entry& e : undo_) ops.insert(ops.end(), e.ops.begin(), e.ops.end());
    return ops;
}

std::optional<HistoryStep> History::undo() { return step(undo_, redo_, true); }

std::optional<HistoryStep> History::redo() { return step(redo_, undo_, false); }

std::optional<HistoryStep> History::step(std::vector<Entry>& from, std::vector<Entry>& to, bool before)
{
    if (from.empty()) return std::nullopt;
    Entry entry = std::move(from.back());
    from.pop_back();
    load(entry);
    HistoryStep out;
    out.leaves = imagesOf(entry.changes, before);
    if (entry.mask) out.mask = before ? entry.mask->before : entry.mask->after;
    to.push_back(std::move(entry));
    spillOver();
    return out;
}

void History::release(Entry& entry)
{
    if (entry.spilled) spilledBytes_ -= entry.bytes;
    else memoryBytes_ -= entry.bytes;
    entry.changes.clear();
}

void History::load(Entry& entry)
{
    if (!entry.spilled) return;
    std::string bytes(std::size_t(entry.bytes), '\0');
    if (std::fseek(spill_, long(entry.fileOffset), SEEK_SET) != 0 || std::fread(bytes.data(), 1, bytes.size(), spill_) != bytes.size())
        throw std::runtime_error("the undo history's spill file could not be read");
    Reader r{bytes};
    uint64_t count = 0;
    r.get(&count, sizeof count);
    entry.changes.resize(std::size_t(count));
    for (LeafChange& c : entry.changes) {
        r.get(c.origin.data(), sizeof c.origin);
        c.before = r.getString();
        c.after = r.getString();
    }
    entry.spilled = false;
    spilledBytes_ -= entry.bytes;
    entry.bytes = bytesOf(entry.changes);
    memoryBytes_ += entry.bytes;
}

void History::spillOver()
{
    // Oldest first: the bottom of the undo stack, then the far end of the redo stack.
    std::vector<Entry*> order;
    for (Entry& e : undo_) order.push_back(&e);
    for (auto it = redo_.begin(); it != redo_.end(); ++it) order.push_back(&*it);
    for (Entry* e : order) {
        if (memoryBytes_ <= limits_.memoryBytes) break;
        if (e->spilled) continue;
        std::string out;
        const uint64_t count = e->changes.size();
        put(out, &count, sizeof count);
        for (const LeafChange& c : e->changes) {
            put(out, c.origin.data(), sizeof c.origin);
            putString(out, c.before);
            putString(out, c.after);
        }
        if (!spill_ && !(spill_ = std::tmpfile())) throw std::runtime_error("no temporary file for the undo history");
        if (std::fseek(spill_, long(fileEnd_), SEEK_SET) != 0 || std::fwrite(out.data(), 1, out.size(), spill_) != out.size())
            throw std::runtime_error("the undo history could not be written to its spill file (disk full?)");
        std::fflush(spill_);
        memoryBytes_ -= e->bytes;
        e->changes.clear();
        e->changes.shrink_to_fit();
        e->spilled = true;
        e->fileOffset = fileEnd_;
        e->bytes = out.size();
        fileEnd_ += out.size();
        spilledBytes_ += out.size();
    }
    // Past the spill limit the oldest edits are forgotten (the file's dead space is not reused: it is
    // dropped when nothing spilled is referenced any more).
    while (spilledBytes_ > limits_.spillBytes && !undo_.empty() && undo_.front().spilled) {
        release(undo_.front());
        for (nlohmann::json& op : undo_.front().ops) forgottenOps_.push_back(std::move(op));
        undo_.erase(undo_.begin());
        ++forgotten_;
        if (spilledBytes_ == 0) {
            std::fclose(spill_);
            spill_ = nullptr;
            fileEnd_ = 0;
        }
    }
}

} // namespace vdbclay
