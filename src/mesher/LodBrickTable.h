// Bricks of the level-of-detail octree (a level and an index) packed into 64 bits, and a map keyed by
// them in an open-addressed table. A view's selection asks a few thousand such questions a frame
// (which bricks it accepted, which neighbours its meshes read), where a node-based hash map's
// allocations and pointer chases cost milliseconds.
//
// Light header: no OpenVDB.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <unordered_map>
#include <utility>
#include <vector>

namespace vdbclay {

/// A brick of the cut: level k, covering level-0 points [64 * 2^k * brick, 64 * 2^k * (brick + 1)].
struct LodBrick {
    int level = 0;
    std::array<int32_t, 3> brick{0, 0, 0};
    friend bool operator==(const LodBrick& a, const LodBrick& b) { return a.level == b.level && a.brick == b.brick; }
};

struct LodBrickHash {
    std::size_t operator()(const LodBrick& b) const
    {
        uint64_t h = uint64_t(uint32_t(b.level)) * 0x9E3779B97F4A7C15ull;
        for (const int32_t c : b.brick) h = (h ^ uint32_t(c)) * 0x100000001B3ull + (h >> 29);
        return std::size_t(h ^ (h >> 32));
    }
};

/// Packs level and brick index into one 64-bit key (19 bits a coordinate, the level above them);
/// false where they do not fit (a brick index beyond +-2^18, a level outside [0, 63)). A key is never
/// all ones.
inline bool packLodBrick(int level, const std::array<int32_t, 3>& brick, uint64_t& key)
{
    constexpr int32_t kReach = 1 << 18;
    if (level < 0 || level >= 63) return false;
    key = uint64_t(level) << 57;
    for (int a = 0; a < 3; ++a) {
        const int32_t c = brick[std::size_t(a)];
        if (c < -kReach || c >= kReach) return false;
        key |= uint64_t(c + kReach) << (19 * a);
    }
    return true;
}

/// A map from bricks to values, insert and look up only (no erase: store a value that says "gone").
/// Keys that do not pack go to a node-based map beside the table.
template <class Value>
class LodBrickMap {
    static_assert(!std::is_same_v<Value, bool>, "values live in a std::vector: use char for flags");

public:
    explicit LodBrickMap(std::size_t expected = 16)
    {
        std::size_t slots = 16;
        while (slots < 2 * expected) slots *= 2;
        resize(slots);
    }

    /// The value of a brick, or null.
    const Value* find(int level, const std::array<int32_t, 3>& brick) const
    {
        uint64_t key;
        if (!packLodBrick(level, brick, key)) {
            const auto it = unpacked_.find(LodBrick{level, brick});
            return it == unpacked_.end() ? nullptr : &it->second;
        }
        const std::size_t i = slotOf(key);
        return keys_[i] == key ? &values_[i] : nullptr;
    }
    Value* find(int level, const std::array<int32_t, 3>& brick)
    {
        return const_cast<Value*>(static_cast<const LodBrickMap&>(*this).find(level, brick));
    }
    bool contains(int level, const std::array<int32_t, 3>& brick) const { return find(level, brick) != nullptr; }

    /// The value of a brick, value-initialized when it was not there; second: whether it was inserted.
    std::pair<Value*, bool> insert(int level, const std::array<int32_t, 3>& brick)
    {
        uint64_t key;
        if (!packLodBrick(level, brick, key)) {
            const auto [it, inserted] = unpacked_.try_emplace(LodBrick{level, brick});
            return {&it->second, inserted};
        }
        std::size_t i = slotOf(key);
        if (keys_[i] == key) return {&values_[i], false};
        if (2 * (used_ + 1) > keys_.size()) {
            resize(2 * keys_.size());
            i = slotOf(key);
        }
        keys_[i] = key;
        values_[i] = Value{};
        ++used_;
        return {&values_[i], true};
    }

    /// Forgets every brick, keeping the table's size (a set refilled every frame allocates nothing).
    void clear()
    {
        std::fill(keys_.begin(), keys_.end(), kEmpty);
        used_ = 0;
        unpacked_.clear();
    }

private:
    static constexpr uint64_t kEmpty = ~uint64_t(0);
    /// The slot holding `key`, or the empty one where it would go (linear probing).
    std::size_t slotOf(uint64_t key) const
    {
        std::size_t i = std::size_t((key * 0x9E3779B97F4A7C15ull) >> shift_);
        while (keys_[i] != key && keys_[i] != kEmpty) i = (i + 1) & (keys_.size() - 1);
        return i;
    }

    void resize(std::size_t slots)
    {
        std::vector<uint64_t> oldKeys(slots, kEmpty);
        std::vector<Value> oldValues(slots);
        oldKeys.swap(keys_);
        oldValues.swap(values_);
        shift_ = 64;
        for (std::size_t s = slots; s > 1; s >>= 1) --shift_;
        for (std::size_t j = 0; j < oldKeys.size(); ++j)
            if (oldKeys[j] != kEmpty) {
                const std::size_t i = slotOf(oldKeys[j]);
                keys_[i] = oldKeys[j];
                values_[i] = std::move(oldValues[j]);
            }
    }

    std::vector<uint64_t> keys_;
    std::vector<Value> values_;
    std::size_t used_ = 0;
    int shift_ = 60;
    std::unordered_map<LodBrick, Value, LodBrickHash> unpacked_;
};

} // namespace vdbclay
