#include "indentsim/output/checkpoint.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "indentsim/base/error.hpp"
#include "indentsim/base/file_system.hpp"

namespace indentsim {

namespace {

constexpr char magic[8] = {'I', 'N', 'D', 'S', 'I', 'M', 'C', 'K'};
constexpr std::size_t header_size = sizeof(magic) + sizeof(std::uint32_t) + sizeof(std::uint64_t);

class ByteWriter {
public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const char*>(&value);
    bytes_.append(p, sizeof(T));
  }
  void put_string(const std::string& s) {
    put<std::uint64_t>(s.size());
    bytes_.append(s);
  }
  template <class T>
  void put_vector(const std::vector<T>& v) {
    put<std::uint64_t>(v.size());
    if (!v.empty()) bytes_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  std::string& bytes() { return bytes_; }

private:
  std::string bytes_;
};

// Every read checks what is left, so a damaged file can only fail cleanly.
class ByteReader {
public:
  ByteReader(const char* data, std::size_t size, const std::string& source) : p_(data), left_(size), source_(source) {}

  template <class T>
  T get(const char* what) {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T), what);
    T value;
    std::memcpy(&value, p_, sizeof(T));
    advance(sizeof(T));
    return value;
  }
  std::string get_string(const char* what) {
    const auto n = get<std::uint64_t>(what);
    need_elements(n, 1, what);
    std::string s(p_, static_cast<std::size_t>(n));
    advance(static_cast<std::size_t>(n));
    return s;
  }
  template <class T>
  std::vector<T> get_vector(const char* what) {
    const auto n = get<std::uint64_t>(what);
    need_elements(n, sizeof(T), what);
    std::vector<T> v(static_cast<std::size_t>(n));
    if (n) std::memcpy(v.data(), p_, static_cast<std::size_t>(n) * sizeof(T));
    advance(static_cast<std::size_t>(n) * sizeof(T));
    return v;
  }
  std::size_t left() const { return left_; }
  [[noreturn]] void fail(const std::string& problem) const { throw InputError(source_, "checkpoint", problem); }

private:
  void need(std::size_t n, const char* what) const {
    if (n > left_) fail(fmt::format("ends inside {} (truncated or damaged)", what));
  }
  void need_elements(std::uint64_t count, std::size_t size, const char* what) const {
    if (count > left_ / size) fail(fmt::format("{} claims {} entries, more than the file holds", what, count));
  }
  void advance(std::size_t n) {
    p_ += n;
    left_ -= n;
  }
  const char* p_;
  std::size_t left_;
  std::string source_;
};

void write_record(ByteWriter& w, const IncrementRecord& r) {
  w.put<std::int32_t>(r.step);
  w.put(r.alpha);
  w.put(r.force);
  w.put(r.half_width);
  w.put<std::int32_t>(r.contact_nodes);
  w.put<std::int64_t>(r.newton_iterations);
  w.put<std::int64_t>(r.factorizations);
  w.put<std::int32_t>(r.cutbacks);
  w.put<std::int64_t>(r.plastic_points);
  w.put(r.max_strain_intensity);
  w.put(r.wall_seconds);
}

IncrementRecord read_record(ByteReader& in) {
  IncrementRecord r;
  r.step = in.get<std::int32_t>("a curve row");
  r.alpha = in.get<double>("a curve row");
  r.force = in.get<double>("a curve row");
  r.half_width = in.get<double>("a curve row");
  r.contact_nodes = in.get<std::int32_t>("a curve row");
  r.newton_iterations = in.get<std::int64_t>("a curve row");
  r.factorizations = in.get<std::int64_t>("a curve row");
  r.cutbacks = in.get<std::int32_t>("a curve row");
  r.plastic_points = in.get<std::int64_t>("a curve row");
  r.max_strain_intensity = in.get<double>("a curve row");
  r.wall_seconds = in.get<double>("a curve row");
  return r;
}

/// Writes one state field (visit_fields) in the checkpoint's encoding.
struct StateWriter {
  ByteWriter& w;
  void operator()(const char*, double x, const char*) { w.put(x); }
  void operator()(const char*, bool b, const char*) { w.put<std::uint8_t>(b); }
  void operator()(const char*, int i, const char*) { w.put<std::int32_t>(i); }
  void operator()(const char*, std::uint64_t i, const char*) { w.put(i); }
  void operator()(const char*, const std::vector<double>& v, const char*) { w.put_vector(v); }
  void operator()(const char*, const std::vector<char>& v, const char*) { w.put_vector(v); }
  void operator()(const char*, const std::vector<std::string>& v, const char*) {
    w.put<std::uint64_t>(v.size());
    for (const auto& text : v) w.put_string(text);
  }
  void operator()(const char*, const NearField& near, const char*) {
    w.put<std::uint8_t>(near.condensed);
    w.put<std::int32_t>(near.contact_nodes);
    w.put<std::int32_t>(near.elements_x);
    w.put<std::int32_t>(near.elements_y);
  }
  void operator()(const char*, const PlasticZoneGrowth& zone, const char*) {
    w.put_vector(zone.depths);
    std::vector<double> widths, depths;
    for (const auto& e : zone.extents) {
      widths.push_back(e.width);
      depths.push_back(e.depth);
    }
    w.put_vector(widths);
    w.put_vector(depths);
  }
};

/// Reads one state field (visit_fields), checking what is left of the file at every read.
struct StateReader {
  ByteReader& in;
  void operator()(const char*, double& x, const char* what) { x = in.get<double>(what); }
  void operator()(const char*, bool& b, const char* what) { b = in.get<std::uint8_t>(what) != 0; }
  void operator()(const char*, int& i, const char* what) { i = in.get<std::int32_t>(what); }
  void operator()(const char*, std::uint64_t& i, const char* what) { i = in.get<std::uint64_t>(what); }
  void operator()(const char*, std::vector<double>& v, const char* what) { v = in.get_vector<double>(what); }
  void operator()(const char*, std::vector<char>& v, const char* what) { v = in.get_vector<char>(what); }
  void operator()(const char*, std::vector<std::string>& v, const char* what) {  // the warnings
    const auto n = in.get<std::uint64_t>(what);
    if (n > in.left()) in.fail("claims more warnings than the file holds");
    // A warning is printed again on resume and written to summary.json: made printable here (a
    // hostile file's ESC or NUL never reaches a terminal) and bounded in length.
    for (std::uint64_t k = 0; k < n; ++k) v.push_back(printable(in.get_string("a warning"), 2000));
  }
  void operator()(const char*, NearField& near, const char* what) {
    near.condensed = in.get<std::uint8_t>(what) != 0;
    near.contact_nodes = in.get<std::int32_t>(what);
    near.elements_x = in.get<std::int32_t>(what);
    near.elements_y = in.get<std::int32_t>(what);
  }
  void operator()(const char*, PlasticZoneGrowth& zone, const char* what) {
    zone.depths = in.get_vector<double>(what);
    const auto widths = in.get_vector<double>(what);
    const auto depths = in.get_vector<double>(what);
    if (widths.size() != depths.size() || widths.size() != zone.depths.size())
      in.fail("its plastic zone growth has lists of different lengths");
    for (std::size_t k = 0; k < widths.size(); ++k) zone.extents.push_back({widths[k], depths[k]});
  }
};

/// The first state field holding a number that is not finite (nullptr: none).
struct NonFiniteField {
  const char* field = nullptr;
  void note(const char* name, bool finite) {
    if (!finite && !field) field = name;
  }
  static bool all_finite(const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  }
  void operator()(const char* name, double x, const char*) { note(name, std::isfinite(x)); }
  void operator()(const char* name, const std::vector<double>& v, const char*) { note(name, all_finite(v)); }
  void operator()(const char* name, const PlasticZoneGrowth& zone, const char*) {
    bool finite = all_finite(zone.depths);
    for (const auto& e : zone.extents) finite = finite && std::isfinite(e.width) && std::isfinite(e.depth);
    note(name, finite);
  }
  template <class T>
  void operator()(const char*, const T&, const char*) {}  // counts, flags, texts
};

/// The content of a checkpoint whose checksum holds (it may have been recomputed after an edit):
/// every number finite, the curve a run's curve (steps 0, 1, 2, ..., starting unloaded), and the
/// state at the curve's last row.  What needs the mesh and the load path is checked in resume_from.
void check_content(const Checkpoint& c, const ByteReader& in) {
  const SimulationState& s = c.state;
  const auto finite = NonFiniteField::all_finite;
  NonFiniteField non_finite;
  visit_fields(s, non_finite);
  if (non_finite.field) in.fail(fmt::format("its state's {} holds a number that is not finite", non_finite.field));
  if (!std::isfinite(c.planned_contact_half_width)) in.fail("its mesh plan is not a finite number");
  if (!finite(c.mesh_x) || !finite(c.mesh_y) || !finite(c.free_surface_depths))
    in.fail("its mesh or summary data hold a number that is not finite");
  if (c.curve.empty()) in.fail("holds no curve row");
  double deepest = 0.0;
  for (std::size_t k = 0; k < c.curve.size(); ++k) {
    const IncrementRecord& r = c.curve[k];
    if (r.step != static_cast<int>(k)) in.fail(fmt::format("its curve row {} is numbered {}", k, r.step));
    if (!std::isfinite(r.alpha) || !std::isfinite(r.force) || !std::isfinite(r.half_width) ||
        !std::isfinite(r.max_strain_intensity) || !std::isfinite(r.wall_seconds))
      in.fail(fmt::format("its curve row {} holds a number that is not finite", k));
    if (r.alpha < 0.0 || r.force < 0.0 || r.half_width < 0.0 || r.contact_nodes < 0 || r.newton_iterations < 0 ||
        r.factorizations < 0 || r.cutbacks < 0 || r.plastic_points < 0)
      in.fail(fmt::format("its curve row {} holds a negative depth, force or count", k));
    deepest = std::max(deepest, r.alpha);
  }
  if (c.curve.front().alpha != 0.0) in.fail("its curve does not start unloaded (alpha = 0)");
  if (c.curve.back().alpha != s.alpha || deepest != s.deepest)
    in.fail("its curve and its state disagree on the depth reached");
  if (s.u.size() > 2 * c.mesh_x.size() * c.mesh_y.size() || (s.has_previous && s.u_previous.size() != s.u.size()) ||
      s.in_contact.size() > c.mesh_x.size())
    in.fail("its state does not fit its mesh");
  const NearField& near = s.near_field;
  if (near.condensed &&
      (near.contact_nodes < 1 || near.contact_nodes > static_cast<int>(c.mesh_x.size()) || near.elements_x < 0 ||
       near.elements_x >= static_cast<int>(c.mesh_x.size()) || near.elements_y < 0 ||
       near.elements_y >= static_cast<int>(c.mesh_y.size())))
    in.fail("its near field does not fit its mesh");
}

}  // namespace

std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t hash) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= p[i];
    hash *= 0x100000001b3ull;
  }
  return hash;
}

std::string serialize(const Checkpoint& c) {
  ByteWriter payload;
  payload.put_string(c.load_case_toml);
  payload.put<std::uint64_t>(fnv1a(c.load_case_toml.data(), c.load_case_toml.size()));
  payload.put(c.planned_contact_half_width);
  payload.put_vector(c.mesh_x);
  payload.put_vector(c.mesh_y);
  visit_fields(c.state, StateWriter{payload});
  payload.put<std::uint64_t>(c.curve.size());
  for (const auto& r : c.curve) write_record(payload, r);
  payload.put_vector(c.free_surface_depths);
  payload.put<std::uint64_t>(c.true_contacts.size());
  for (const auto& [step, truth] : c.true_contacts) {
    payload.put<std::int32_t>(step);
    payload.put<std::uint8_t>(truth.stiffness ? 1 : 0);
    payload.put(truth.stiffness.value_or(0.0));
    payload.put(truth.half_width);
  }

  ByteWriter file;
  file.bytes().append(magic, sizeof(magic));
  file.put<std::uint32_t>(checkpoint_format_version);
  file.put<std::uint64_t>(payload.bytes().size());
  file.bytes().append(payload.bytes());
  file.put<std::uint64_t>(fnv1a(file.bytes().data(), file.bytes().size()));
  return std::move(file.bytes());
}

Checkpoint deserialize(const std::string& bytes, const std::string& source) {
  const auto fail = [&](const std::string& problem) { throw InputError(source, "checkpoint", problem); };
  if (bytes.size() < header_size + sizeof(std::uint64_t))
    fail(fmt::format("is {} bytes long, too short to be a checkpoint", bytes.size()));
  if (std::memcmp(bytes.data(), magic, sizeof(magic)) != 0) fail("is not an indentsim checkpoint (bad magic bytes)");
  std::uint32_t version;
  std::memcpy(&version, bytes.data() + sizeof(magic), sizeof(version));
  if (version != checkpoint_format_version)
    fail(fmt::format("was written in checkpoint format {}; this indentsim reads format {}", version,
                     checkpoint_format_version));
  std::uint64_t length;
  std::memcpy(&length, bytes.data() + sizeof(magic) + sizeof(version), sizeof(length));
  if (length != bytes.size() - header_size - sizeof(std::uint64_t))
    fail(fmt::format("holds {} bytes of data where its header promises {} (truncated or damaged)",
                     bytes.size() - std::min(bytes.size(), header_size + sizeof(std::uint64_t)), length));
  std::uint64_t stored;
  std::memcpy(&stored, bytes.data() + bytes.size() - sizeof(stored), sizeof(stored));
  if (stored != fnv1a(bytes.data(), bytes.size() - sizeof(stored)))
    fail("fails its checksum (the file is damaged)");

  ByteReader in(bytes.data() + header_size, static_cast<std::size_t>(length), source);
  Checkpoint c;
  c.load_case_toml = in.get_string("the load case");
  if (in.get<std::uint64_t>("the load case hash") != fnv1a(c.load_case_toml.data(), c.load_case_toml.size()))
    in.fail("its load case does not match the load case hash");
  c.planned_contact_half_width = in.get<double>("the mesh plan");
  c.mesh_x = in.get_vector<double>("the mesh");
  c.mesh_y = in.get_vector<double>("the mesh");
  visit_fields(c.state, StateReader{in});
  const SimulationState& s = c.state;
  const auto rows = in.get<std::uint64_t>("the curve");
  if (rows > in.left()) in.fail("claims more curve rows than the file holds");
  for (std::uint64_t k = 0; k < rows; ++k) c.curve.push_back(read_record(in));
  c.free_surface_depths = in.get_vector<double>("the summary data");
  const auto truths = in.get<std::uint64_t>("the true contacts");
  if (truths > in.left()) in.fail("claims more true contacts than the file holds");
  for (std::uint64_t k = 0; k < truths; ++k) {
    const int step = in.get<std::int32_t>("a true contact");
    const bool has_stiffness = in.get<std::uint8_t>("a true contact") != 0;
    const double stiffness = in.get<double>("a true contact");
    TrueContact t;
    if (has_stiffness) t.stiffness = stiffness;
    t.half_width = in.get<double>("a true contact");
    if (!(step > 0 && static_cast<std::uint64_t>(step) < rows) || !std::isfinite(stiffness) || !(t.half_width >= 0.0) ||
        !std::isfinite(t.half_width) || (has_stiffness && !(stiffness > 0.0)))
      in.fail(fmt::format("its true contact {} is not at a row of its curve or not a finite positive number", k));
    c.true_contacts.emplace_back(step, t);
  }
  if (in.left() != 0) in.fail(fmt::format("has {} unexplained bytes at its end", in.left()));
  if (c.free_surface_depths.size() != c.curve.size() || s.rows != static_cast<int>(c.curve.size()) ||
      s.next_target != c.curve.size())
    in.fail("its curve, summary and state disagree on the number of increments");
  check_content(c, in);
  return c;
}

void write_checkpoint(const std::filesystem::path& file, const Checkpoint& checkpoint) {
  const std::string bytes = serialize(checkpoint);
  const std::filesystem::path temporary = file.string() + ".tmp";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw_io_error(temporary, "creating", errno);
  try {
    const std::size_t half = bytes.size() / 2;
    write_all(fd, bytes.data(), half, temporary);
    inject_fault("checkpoint");  // robustness tests: die mid-write
    write_all(fd, bytes.data() + half, bytes.size() - half, temporary);
    if (::fsync(fd) != 0) throw_io_error(temporary, "flushing (fsync)", errno);
  } catch (...) {
    ::close(fd);
    ::unlink(temporary.c_str());  // the previous checkpoints stay as they were
    throw;
  }
  ::close(fd);
  if (::rename(temporary.c_str(), file.c_str()) != 0) {
    const int error = errno;
    ::unlink(temporary.c_str());
    throw_io_error(file, "renaming a temporary file to", error);
  }
  // Make the rename itself durable.
  const int dir = ::open(file.parent_path().empty() ? "." : file.parent_path().c_str(), O_RDONLY | O_CLOEXEC);
  if (dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
}

Checkpoint read_checkpoint(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw InputError(file.string(), "checkpoint", "is not a readable file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "checkpoint", "cannot be opened");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return deserialize(bytes.str(), file.string());
}

}  // namespace indentsim
