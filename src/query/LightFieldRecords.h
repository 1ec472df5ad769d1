// The quantized light fields of a library's indexed models, in their index's order, kept beside the
// library (LIBRARY.lightfield.records) as fixed-size records and mapped into memory: a query compares
// each shortlisted model's light field in place instead of seeking it in SQLite (4-5 us a row, most of
// a combined query's time). A cache like FLANN's saved index: its header names the library (its identity)
// and the models it holds, it is made again from the stored vectors when missing or stale, and where it
// cannot be written the records are held in memory instead.
#pragma once

#include "query/LightField.h"

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace vdbclay::query {

class LightFieldRecords {
public:
    /// The records in `path` if its header names exactly `models` (in this order) of the library
    /// `identity` and its size matches; nullptr for a missing, stale, foreign or truncated file.
    static std::unique_ptr<LightFieldRecords> map(const std::string& path, const std::string& identity, const std::vector<int64_t>& models);

    LightFieldRecords(const LightFieldRecords&) = delete;
    LightFieldRecords& operator=(const LightFieldRecords&) = delete;
    ~LightFieldRecords();

    std::size_t size() const { return count_; }
    /// Record i: kLightFieldLength bytes.
    const uint8_t* operator[](std::size_t i) const { return data_ + i * kLightFieldLength; }

private:
    friend class LightFieldRecordsWriter;
    LightFieldRecords() = default;

    const uint8_t* data_ = nullptr;
    std::size_t count_ = 0;
    void* mapping_ = nullptr; // the whole file, when mapped
    std::size_t mappedBytes_ = 0;
    std::vector<uint8_t> held_; // the records, when the file could not be written
};

/// Writes the records of `models` of the library `identity`, one append() each in their order, under a
/// temporary name beside `path` that finish() renames over it (a reader never sees half a file), then
/// maps it. With an empty `path`, or where the file cannot be made, the records are held in memory.
/// finish() throws std::runtime_error where a file was made but could not be completed (then write to
/// memory).
class LightFieldRecordsWriter {
public:
    LightFieldRecordsWriter(std::string path, const std::string& identity, std::vector<int64_t> models);
    ~LightFieldRecordsWriter();
    void append(const QuantizedLightField& record);
    /// Throws std::logic_error unless every model's record was appended.
    std::unique_ptr<LightFieldRecords> finish();

private:
    std::string path_, temporary_;
    std::vector<int64_t> models_;
    std::size_t appended_ = 0;
    std::FILE* file_ = nullptr; // null once writing failed: the records are then kept in held_
    std::vector<uint8_t> held_;
};

} // namespace vdbclay::query
