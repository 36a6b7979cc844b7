#include "softhd/control/run_log.hpp"

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "softhd/error.hpp"
#include "softhd/io/atomic_file.hpp"

namespace softhd {

namespace {

constexpr char kMagic[9] = "SHDLOG01";
constexpr std::uint64_t kFnvOffset = 1469598103934665603ull, kFnvPrime = 1099511628211ull;

std::uint64_t fnv1a(const void* data, std::size_t bytes, std::uint64_t h = kFnvOffset) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t k = 0; k < bytes; ++k) h = (h ^ p[k]) * kFnvPrime;
  return h;
}

// Little-endian encoding (the machines softhd runs on are little-endian; the bytes are
// copied as they are, so the log is bitwise).
class Encoder {
 public:
  template <class T>
  void put(T v) {
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void put_vector(const double* data, std::uint64_t n) {
    put<std::uint64_t>(n);
    out.append(reinterpret_cast<const char*>(data), n * sizeof(double));
  }
  void put_string(const std::string& s) {
    put<std::uint64_t>(s.size());
    out += s;
  }
  std::string out;
};

// Bounds-checked reading of one record's payload; every failure names the offset.
class Decoder {
 public:
  Decoder(const std::string& bytes, std::size_t begin, std::size_t end, std::string where)
      : bytes_(bytes), pos_(begin), end_(end), where_(std::move(where)) {}
  [[noreturn]] void fail(const std::string& what) const {
    throw FileError(where_ + ": " + what + " at byte " + std::to_string(pos_));
  }
  template <class T>
  T get() {
    if (end_ - pos_ < sizeof(T)) fail("record too short");
    T v;
    std::memcpy(&v, bytes_.data() + pos_, sizeof v);
    pos_ += sizeof v;
    return v;
  }
  std::uint64_t count(std::uint64_t item_bytes) {
    const auto n = get<std::uint64_t>();
    if (n > (end_ - pos_) / item_bytes) fail("a length runs past the record");
    return n;
  }
  Eigen::VectorXd vector() {
    const std::uint64_t n = count(sizeof(double));
    Eigen::VectorXd v(static_cast<Eigen::Index>(n));
    if (n) std::memcpy(v.data(), bytes_.data() + pos_, n * sizeof(double));
    pos_ += n * sizeof(double);
    return v;
  }
  std::string string() {
    const std::uint64_t n = count(1);
    std::string s = bytes_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  void finish() const {
    if (pos_ != end_) fail("trailing bytes in a record");
  }

 private:
  const std::string& bytes_;
  std::size_t pos_, end_;
  std::string where_;
};

std::string encode_fingerprint(const RunFingerprint& f) {
  Encoder e;
  e.put<std::uint64_t>(f.size());
  for (const auto& [key, value] : f) {
    e.put_string(key);
    e.put_string(value);
  }
  return e.out;
}

std::string encode_evaluation(const LoggedEvaluation& ev) {
  const ShapeEvaluation& r = ev.result;
  Encoder e;
  // Bit 1: the evaluation's status is ok (else state_failed); bit 2: a pose twist and the
  // inner iterations follow the failure (a camera-frame target's evaluation).
  const bool pose = r.pose_twist.size() != 0;
  e.put<std::uint8_t>((ev.gradient ? 1 : 0) | (r.status == EvaluationStatus::ok ? 2 : 0) |
                      (pose ? 4 : 0));
  e.put<double>(ev.seconds);
  e.put<std::int32_t>(r.newton_iterations);
  e.put<std::int32_t>(r.factorizations);
  for (double v : {r.J, r.rho, r.A, r.B, r.regularisation, r.seconds_state, r.seconds_distance,
                   r.seconds_adjoint})
    e.put<double>(v);
  e.put_vector(ev.x.data(), static_cast<std::uint64_t>(ev.x.size()));
  e.put_vector(r.gradient.data(), static_cast<std::uint64_t>(r.gradient.size()));
  e.put_string(r.failure);
  if (pose) {
    e.put_vector(r.pose_twist.data(), static_cast<std::uint64_t>(r.pose_twist.size()));
    e.put<std::int32_t>(r.pose_iterations);
  }
  return e.out;
}

LoggedEvaluation decode_evaluation(Decoder& d) {
  LoggedEvaluation ev;
  ShapeEvaluation& r = ev.result;
  const auto flags = d.get<std::uint8_t>();
  if (flags > 7) d.fail("unknown evaluation flags");
  ev.gradient = flags & 1;
  r.status = flags & 2 ? EvaluationStatus::ok : EvaluationStatus::state_failed;
  ev.seconds = d.get<double>();
  r.newton_iterations = d.get<std::int32_t>();
  r.factorizations = d.get<std::int32_t>();
  for (double* v : {&r.J, &r.rho, &r.A, &r.B, &r.regularisation, &r.seconds_state,
                    &r.seconds_distance, &r.seconds_adjoint})
    *v = d.get<double>();
  ev.x = d.vector();
  r.gradient = d.vector();
  r.failure = d.string();
  if (flags & 4) {
    r.pose_twist = d.vector();
    r.pose_iterations = d.get<std::int32_t>();
    if (!r.pose_twist.allFinite() || r.pose_iterations < 0 ||
        (r.pose_twist.size() != 6 && r.pose_twist.size() != 7))
      d.fail("an evaluation's pose twist is not 6 or 7 finite values");
  }
  if (!ev.x.allFinite() || !std::isfinite(ev.seconds) || r.newton_iterations < 0 ||
      r.factorizations < 0)
    d.fail("an evaluation holds non-finite or negative values");
  if (ev.x.size() == 0) d.fail("an evaluation without a control");
  if (r.status == EvaluationStatus::ok && ev.gradient && r.gradient.size() != ev.x.size())
    d.fail("an evaluation's gradient has the wrong size");
  return ev;
}

// A Hessian-vector product: flags (bit 1: ok), seconds, x, v, H v, the failure.
std::string encode_product(const LoggedEvaluation& ev) {
  const ShapeEvaluation& r = ev.result;
  Encoder e;
  e.put<std::uint8_t>(r.status == EvaluationStatus::ok ? 2 : 0);
  e.put<double>(ev.seconds);
  e.put_vector(ev.x.data(), static_cast<std::uint64_t>(ev.x.size()));
  e.put_vector(ev.direction.data(), static_cast<std::uint64_t>(ev.direction.size()));
  e.put_vector(r.gradient.data(), static_cast<std::uint64_t>(r.gradient.size()));
  e.put_string(r.failure);
  return e.out;
}

LoggedEvaluation decode_product(Decoder& d) {
  LoggedEvaluation ev;
  ShapeEvaluation& r = ev.result;
  const auto flags = d.get<std::uint8_t>();
  if (flags != 0 && flags != 2) d.fail("unknown product flags");
  r.status = flags & 2 ? EvaluationStatus::ok : EvaluationStatus::state_failed;
  ev.seconds = d.get<double>();
  ev.x = d.vector();
  ev.direction = d.vector();
  r.gradient = d.vector();
  r.failure = d.string();
  if (ev.x.size() == 0 || ev.direction.size() != ev.x.size() || !ev.x.allFinite() ||
      !ev.direction.allFinite() || !std::isfinite(ev.seconds))
    d.fail("a Hessian-vector product without a finite control and direction");
  if (r.status == EvaluationStatus::ok && r.gradient.size() != ev.x.size())
    d.fail("a Hessian-vector product of the wrong size");
  return ev;
}

void encode_state(Encoder& e, const fe::State& state) {
  e.put_vector(state.u.data(), static_cast<std::uint64_t>(state.u.size()));
  e.put<std::uint64_t>(static_cast<std::uint64_t>(state.m_qp.rows()));
  e.put_vector(state.m_qp.data(), static_cast<std::uint64_t>(state.m_qp.size()));
}

fe::State decode_state(Decoder& d) {
  fe::State state;
  state.u = d.vector();
  const auto rows = d.get<std::uint64_t>();
  const Eigen::VectorXd qp = d.vector();
  if (rows == 0 ? qp.size() != 0 : qp.size() % rows != 0)
    d.fail("a warm-start state has an inconsistent shape");
  state.m_qp = Eigen::Map<const Eigen::MatrixXd>(qp.data(), static_cast<Eigen::Index>(rows),
                                                 rows ? qp.size() / rows : 0);
  if (!state.u.allFinite() || !state.m_qp.allFinite()) d.fail("a state holds non-finite values");
  return state;
}

std::string encode_snapshot(const RunSnapshot& s) {
  Encoder e;
  e.put<std::int64_t>(s.evaluations);
  e.put<std::int64_t>(s.iterations);
  e.put<std::uint64_t>(s.states.size());
  for (const WarmStart& w : s.states) {
    e.put_vector(w.m.data(), static_cast<std::uint64_t>(w.m.size()));
    encode_state(e, w.state);
  }
  encode_state(e, s.best);
  return e.out;
}

RunSnapshot decode_snapshot(Decoder& d) {
  RunSnapshot s;
  s.evaluations = d.get<std::int64_t>();
  s.iterations = d.get<std::int64_t>();
  const std::uint64_t n = d.count(4 * sizeof(std::uint64_t));
  for (std::uint64_t k = 0; k < n; ++k) {
    WarmStart w;
    w.m = d.vector();
    w.state = decode_state(d);
    s.states.push_back(std::move(w));
  }
  s.best = decode_state(d);
  return s;
}

}  // namespace

std::string content_hash(const void* data, std::size_t bytes) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(fnv1a(data, bytes)));
  return text;
}

std::string exact_text(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "%a", value);
  return text;
}

namespace {

constexpr char kStatesMagic[9] = "SHDSTA01";
constexpr std::size_t kFrame = 1 + 8 + 8;  // kind, length, checksum

// Calls on_record(kind, decoder) for every whole record after the 8-byte magic. A torn
// last record (the run was killed while writing it) ends the walk; any other bad checksum
// is corruption.
template <class F>
void walk_records(const std::string& bytes, const std::string& source, F&& on_record) {
  std::size_t pos = 8;
  while (pos < bytes.size()) {
    std::uint64_t length = 0;
    if (bytes.size() - pos >= kFrame) std::memcpy(&length, bytes.data() + pos + 1, 8);
    const bool complete = bytes.size() - pos >= kFrame && length <= bytes.size() - pos - kFrame;
    std::uint64_t stored = 0, sum = 0;
    if (complete) {
      std::memcpy(&stored, bytes.data() + pos + 9 + length, 8);
      sum = fnv1a(bytes.data() + pos, 9 + length);
    }
    const std::size_t next = complete ? pos + kFrame + length : bytes.size();
    if (!complete || stored != sum) {
      if (next == bytes.size()) return;
      throw FileError(source + ": corrupt record at byte " + std::to_string(pos));
    }
    Decoder d(bytes, pos + 9, pos + 9 + length, source);
    on_record(bytes[pos], d);
    d.finish();
    pos = next;
  }
}

std::string read_bytes(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw FileError(path + ": is a directory, not a checkpoint");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError(path + ": cannot open the checkpoint");
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw FileError(path + ": read error");
  return s.str();
}

std::string states_path(const std::string& path) { return path + ".states"; }

}  // namespace

RunLog parse_run_log(const std::string& bytes, const std::string& source) {
  if (bytes.size() < 8 || bytes.compare(0, 8, kMagic, 8) != 0)
    throw FileError(source + ": not a softhd checkpoint (no SHDLOG01 header)");
  RunLog log;
  bool has_fingerprint = false;
  walk_records(bytes, source, [&](char kind, Decoder& d) {
    if (!has_fingerprint && kind != 'H') d.fail("the fingerprint record must come first");
    if (kind == 'H') {
      if (has_fingerprint) d.fail("a second fingerprint record");
      log.run_id = d.get<std::uint64_t>();
      const std::uint64_t n = d.count(16);
      for (std::uint64_t k = 0; k < n; ++k) {
        std::string key = d.string();
        log.fingerprint[key] = d.string();
      }
      has_fingerprint = true;
    } else if (kind == 'E') {
      log.evaluations.push_back(decode_evaluation(d));
    } else if (kind == 'P') {
      log.evaluations.push_back(decode_product(d));
    } else {
      d.fail("unknown record kind");
    }
  });
  if (!has_fingerprint) throw FileError(source + ": the checkpoint has no fingerprint record");
  return log;
}

RunSnapshot parse_run_states(const std::string& bytes, const std::string& source,
                             std::uint64_t* run_id) {
  if (bytes.size() < 8 || bytes.compare(0, 8, kStatesMagic, 8) != 0)
    throw FileError(source + ": not a softhd checkpoint's states (no SHDSTA01 header)");
  RunSnapshot s;
  int records = 0;
  walk_records(bytes, source, [&](char kind, Decoder& d) {
    if (kind != 'S' || records++ > 0) d.fail("expected one states record");
    *run_id = d.get<std::uint64_t>();
    s = decode_snapshot(d);
  });
  if (records != 1) throw FileError(source + ": incomplete states record");
  if (s.evaluations < 0 || s.iterations < 0 || s.iterations > s.evaluations)
    throw FileError(source + ": inconsistent counts (" + std::to_string(s.evaluations) +
                    " evaluations, " + std::to_string(s.iterations) + " iterations)");
  return s;
}

void attach_states(RunLog& log, std::uint64_t run_id, RunSnapshot states,
                   const std::string& source) {
  if (run_id != log.run_id)
    throw FileError(source + ": the states belong to another run than the log");
  if (states.evaluations > static_cast<std::int64_t>(log.evaluations.size()))
    throw FileError(source + ": the states' counts (" + std::to_string(states.evaluations) +
                    " evaluations) do not match the " + std::to_string(log.evaluations.size()) +
                    " evaluations logged");
  // Evaluations after the states were written are made again on resume.
  log.evaluations.resize(static_cast<std::size_t>(states.evaluations));
  log.snapshot = std::move(states);
  log.has_snapshot = true;
}

RunLog read_run_log(const std::string& path) {
  RunLog log = parse_run_log(read_bytes(path), path);
  const std::string states = states_path(path);
  std::error_code ec;
  if (std::filesystem::exists(states, ec)) {
    std::uint64_t run_id = 0;
    RunSnapshot s = parse_run_states(read_bytes(states), states, &run_id);
    attach_states(log, run_id, std::move(s), states);
  } else {
    log.evaluations.clear();  // killed before its first iteration: nothing to replay
  }
  return log;
}

void check_fingerprint(const RunFingerprint& stored, const RunFingerprint& current,
                       const std::string& source) {
  auto quote = [](const RunFingerprint& f, const std::string& key) {
    const auto it = f.find(key);
    return it == f.end() ? std::string("(absent)") : it->second;
  };
  RunFingerprint keys = stored;
  keys.insert(current.begin(), current.end());
  for (const auto& kv : keys) {
    const std::string a = quote(stored, kv.first), b = quote(current, kv.first);
    if (a != b)
      throw InvalidArgument(source + " was written for another run: " + kv.first +
                            " differs (checkpoint " + a + ", now " + b + ")");
  }
}

RunLogWriter::RunLogWriter(const std::string& path, const RunFingerprint& fingerprint,
                           const RunLog* replayed)
    : path_(path) {
  if (replayed) {
    run_id_ = replayed->run_id;
  } else {
    std::random_device device;
    run_id_ =
        (std::uint64_t(device()) << 32) ^ device() ^
        static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
    std::error_code ec;
    std::filesystem::remove(states_path(path), ec);  // an earlier run's
  }
  const std::string tmp = path + ".tmp";
  file_ = std::fopen(tmp.c_str(), "wb");
  if (!file_)
    throw FileError(path + ": cannot write the checkpoint (" + std::strerror(errno) + ")");
  try {
    if (std::fwrite(kMagic, 1, 8, file_) != 8)
      throw FileError(path + ": cannot write the checkpoint (" + std::strerror(errno) + ")");
    Encoder h;
    h.put<std::uint64_t>(run_id_);
    write_record('H', h.out + encode_fingerprint(fingerprint));
    if (replayed)
      for (const LoggedEvaluation& e : replayed->evaluations) append(e);
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) throw FileError(path + ": cannot write the checkpoint (" + ec.message() + ")");
  } catch (...) {  // no half-written temporary left behind
    std::fclose(file_);
    file_ = nullptr;
    std::remove(tmp.c_str());
    throw;
  }
}

RunLogWriter::~RunLogWriter() {
  if (file_) std::fclose(file_);
}

void RunLogWriter::append(const LoggedEvaluation& evaluation) {
  if (evaluation.direction.size() != 0)
    write_record('P', encode_product(evaluation));
  else
    write_record('E', encode_evaluation(evaluation));
}

void RunLogWriter::write_states(const RunSnapshot& snapshot) {
  Encoder e;
  e.put<std::uint64_t>(run_id_);
  const std::string payload = e.out + encode_snapshot(snapshot);
  Encoder r;
  r.out.assign(kStatesMagic, 8);
  r.put<char>('S');
  r.put<std::uint64_t>(payload.size());
  r.out += payload;
  r.put<std::uint64_t>(fnv1a(r.out.data() + 8, r.out.size() - 8));
  const std::string path = states_path(path_);
  write_file_atomically(path, r.out);
}

void RunLogWriter::write_record(char kind, const std::string& payload) {
  Encoder e;
  e.put<char>(kind);
  e.put<std::uint64_t>(payload.size());
  e.out += payload;
  e.put<std::uint64_t>(fnv1a(e.out.data(), e.out.size()));
  if (std::fwrite(e.out.data(), 1, e.out.size(), file_) != e.out.size() || std::fflush(file_) != 0)
    throw FileError(path_ + ": cannot append to the checkpoint (" + std::strerror(errno) + ")");
}

}  // namespace softhd
