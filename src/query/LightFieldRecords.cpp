#include "query/LightFieldRecords.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace vdbclay::query {

namespace {

constexpr std::array<char, 8> kMagic{'V', 'C', 'L', 'F', 'R', 'E', 'C', '1'};

/// The header: the magic, then the record count, the record length and a hash of the models' ids, each
/// 64 bits little-endian (this machine's order; a file from another order reads as stale).
struct Header {
    std::array<char, 8> magic = kMagic;
    uint64_t count = 0, recordLength = kLightFieldLength, models = 0;
};
static_assert(sizeof(Header) == 32);

/// FNV-1a over the library's identity and the ids' bytes: which models of which library, in which order.
uint64_t modelsHash(const std::string& identity, const std::vector<int64_t>& models)
{
    uint64_t h = 14695981039346656037ull;
    const auto mix = [&](uint64_t value) { h = (h ^ value) * 1099511628211ull; };
    for (char c : identity) mix(uint8_t(c));
    mix(identity.size());
    for (int64_t id : models)
        for (int b = 0; b < 8; ++b) mix((uint64_t(id) >> (8 * b)) & 0xffu);
    return h;
}

Header headerFor(const std::string& identity, const std::vector<int64_t>& models)
{
    Header h;
    h.count = models.size();
    h.models = modelsHash(identity, models);
    return h;
}

} // namespace

std::unique_ptr<LightFieldRecords> LightFieldRecords::map(const std::string& path, const std::string& identity, const std::vector<int64_t>& models)
{
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return nullptr;
    const Header expected = headerFor(identity, models);
    Header found;
    struct stat st {};
    const std::size_t bytes = sizeof(Header) + models.size() * kLightFieldLength;
    const bool usable = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && uint64_t(st.st_size) == bytes &&
                        ::pread(fd, &found, sizeof found, 0) == ssize_t(sizeof found) && std::memcmp(&found, &expected, sizeof found) == 0;
    void* mapping = usable ? ::mmap(nullptr, bytes, PROT_READ, MAP_SHARED, fd, 0) : MAP_FAILED;
    ::close(fd);
    if (mapping == MAP_FAILED) return nullptr;
    std::unique_ptr<LightFieldRecords> out(new LightFieldRecords());
    out->mapping_ = mapping;
    out->mappedBytes_ = bytes;
    out->data_ = static_cast<const uint8_t*>(mapping) + sizeof(Header);
    out->count_ = models.size();
    return out;
}

LightFieldRecords::~LightFieldRecords()
{
    if (mapping_) ::munmap(mapping_, mappedBytes_);
}

LightFieldRecordsWriter::LightFieldRecordsWriter(std::string path, const std::string& identity, std::vector<int64_t> models)
    : path_(std::move(path)), temporary_(path_ + ".new-" + std::to_string(::getpid())), models_(std::move(models))
{
    if (!path_.empty()) file_ = std::fopen(temporary_.c_str(), "w+b");
    const Header header = headerFor(identity, models_);
    if (file_ && std::fwrite(&header, sizeof header, 1, file_) != 1) {
        std::fclose(file_);
        file_ = nullptr;
        std::remove(temporary_.c_str());
    }
    if (!file_) held_.reserve(models_.size() * kLightFieldLength);
}

LightFieldRecordsWriter::~LightFieldRecordsWriter()
{
    if (file_) {
        std::fclose(file_);
        std::remove(temporary_.c_str());
    }
}

void LightFieldRecordsWriter::append(const QuantizedLightField& record)
{
    if (record.size() != kLightFieldLength) throw std::invalid_argument("not a light-field descriptor");
    if (appended_ == models_.size()) throw std::logic_error("more light-field records than models");
    if (file_ && std::fwrite(record.data(), 1, record.size(), file_) != record.size()) {
        // Out of space: what was written comes back into memory, and the rest follows it there.
        held_.resize(appended_ * kLightFieldLength);
        const bool readBack = std::fflush(file_) == 0 && std::fseek(file_, long(sizeof(Header)), SEEK_SET) == 0 &&
                              std::fread(held_.data(), 1, held_.size(), file_) == held_.size();
        std::fclose(file_);
        file_ = nullptr;
        std::remove(temporary_.c_str());
        if (!readBack) throw std::runtime_error("cannot keep the light fields' records: " + std::string(std::strerror(errno)));
    }
    if (!file_) held_.insert(held_.end(), record.begin(), record.end());
    ++appended_;
}

std::unique_ptr<LightFieldRecords> LightFieldRecordsWriter::finish()
{
    if (appended_ != models_.size()) throw std::logic_error("light-field records missing");
    std::unique_ptr<LightFieldRecords> out(new LightFieldRecords());
    out->count_ = models_.size();
    if (file_) {
        // Mapped through the descriptor written, so another process's file renamed over it since is not read.
        const std::size_t bytes = sizeof(Header) + models_.size() * kLightFieldLength;
        void* mapping = MAP_FAILED;
        if (std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0) {
            if (std::rename(temporary_.c_str(), path_.c_str()) != 0) std::remove(temporary_.c_str()); // used once, then gone
            mapping = ::mmap(nullptr, bytes, PROT_READ, MAP_SHARED, ::fileno(file_), 0);
        } else {
            std::remove(temporary_.c_str());
        }
        std::fclose(file_);
        file_ = nullptr;
        if (mapping == MAP_FAILED) throw std::runtime_error("cannot keep the light fields' records beside '" + path_ + "'");
        out->mapping_ = mapping;
        out->mappedBytes_ = bytes;
        out->data_ = static_cast<const uint8_t*>(mapping) + sizeof(Header);
        return out;
    }
    out->held_ = std::move(held_);
    out->data_ = out->held_.data();
    return out;
}

} // namespace vdbclay::query
