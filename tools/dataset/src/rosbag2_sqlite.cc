// rosbag2's sqlite3 storage (.db3): a `topics` table (id, name, type,
// serialization_format, ...) and a `messages` table (id, topic_id, timestamp,
// data), read in id (insertion) order one row at a time, and written with
// the layout every ROS 2 release reads (no schema table: version 2).
#include <filesystem>
#include <map>

#include <sqlite3.h>

#include "ros2_messages.h"
#include "ros2_storage.h"

namespace vio::tools::ros2 {
namespace {

class Database {
 public:
  Database(const std::string& path, int flags) : path_(path) {
    if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) Fail("cannot open");
  }
  ~Database() {
    sqlite3_finalize(statement_);
    sqlite3_close(db_);
  }
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  [[noreturn]] void Fail(const std::string& what) const {
    throw DatasetError(path_ + ": " + what + ": " + (db_ ? sqlite3_errmsg(db_) : "no database") +
                       " (not a rosbag2 sqlite3 file, or truncated or corrupt)");
  }
  void Exec(const std::string& sql) {
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK) Fail("cannot run " + sql);
  }
  /// Prepares the one statement this database steps through.
  void Prepare(const std::string& sql) {
    sqlite3_finalize(statement_);
    statement_ = nullptr;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &statement_, nullptr) != SQLITE_OK) Fail("cannot read");
  }
  /// True for a row, false at the end.
  bool Step() {
    const int rc = sqlite3_step(statement_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    Fail("cannot read a row");
  }
  sqlite3_stmt* statement() { return statement_; }

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* statement_ = nullptr;
};

std::string Text(sqlite3_stmt* s, int column) {
  const unsigned char* text = sqlite3_column_text(s, column);
  return text ? reinterpret_cast<const char*>(text) : "";
}

class SqliteReader final : public MessageReader {
 public:
  SqliteReader(const std::string& path, const std::set<std::string>& wanted)
      : db_(path, SQLITE_OPEN_READONLY) {
    db_.Prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id");
    std::string ids;
    while (db_.Step()) {
      const std::int64_t id = sqlite3_column_int64(db_.statement(), 0);
      Topic& topic = topics_[id];
      topic.name = Text(db_.statement(), 1);
      topic.type = CanonicalType(Text(db_.statement(), 2));
      topic.encoding = Text(db_.statement(), 3);
      if (wanted.empty() || wanted.count(topic.name)) ids += (ids.empty() ? "" : ",") + std::to_string(id);
    }
    db_.Prepare("SELECT topic_id, timestamp, data, id FROM messages" +
                (wanted.empty() ? std::string() : " WHERE topic_id IN (" + ids + ")") + " ORDER BY id");
  }

  bool Next(Message* message) override {
    if (!db_.Step()) return false;
    sqlite3_stmt* s = db_.statement();
    const auto topic = topics_.find(sqlite3_column_int64(s, 0));
    if (topic == topics_.end()) db_.Fail("a message of topic id " + std::to_string(sqlite3_column_int64(s, 0)) +
                                         " that the topics table does not list");
    message->topic = &topic->second;
    message->log_time_ns = sqlite3_column_int64(s, 1);
    message->data = static_cast<const std::uint8_t*>(sqlite3_column_blob(s, 2));
    message->size = static_cast<size_t>(sqlite3_column_bytes(s, 2));
    place_.record = static_cast<std::uint64_t>(sqlite3_column_int64(s, 3));
    return true;
  }

  MessagePlace Place() const override { return place_; }

  std::vector<Topic> Topics() const override {
    std::vector<Topic> topics;
    for (const auto& [id, topic] : topics_) topics.push_back(topic);
    return topics;
  }

 private:
  Database db_;
  std::map<std::int64_t, Topic> topics_;
  MessagePlace place_;  ///< of the last message
};

// Messages read again by their row ids.
class SqliteFetcher final : public MessageFetcher {
 public:
  explicit SqliteFetcher(const std::string& path) : db_(path, SQLITE_OPEN_READONLY) {
    db_.Prepare("SELECT timestamp, data FROM messages WHERE id = ?");
  }

  void Fetch(const MessagePlace& place, Message* message) override {
    sqlite3_stmt* s = db_.statement();
    sqlite3_reset(s);
    sqlite3_bind_int64(s, 1, static_cast<std::int64_t>(place.record));
    if (!db_.Step()) db_.Fail("no message of id " + std::to_string(place.record) + " any more");
    message->log_time_ns = sqlite3_column_int64(s, 0);
    message->data = static_cast<const std::uint8_t*>(sqlite3_column_blob(s, 1));
    message->size = static_cast<size_t>(sqlite3_column_bytes(s, 1));
  }

 private:
  Database db_;
};

class SqliteWriter final : public MessageWriter {
 public:
  SqliteWriter(const std::string& path, const std::vector<Topic>& topics)
      : db_(Fresh(path), SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE) {
    db_.Exec("PRAGMA journal_mode=OFF; PRAGMA synchronous=OFF; BEGIN");
    db_.Exec("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
             "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL)");
    db_.Exec("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
             "timestamp INTEGER NOT NULL, data BLOB NOT NULL)");
    db_.Exec("CREATE INDEX timestamp_idx ON messages (timestamp ASC)");
    db_.Prepare("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')");
    for (size_t i = 0; i < topics.size(); ++i) {
      sqlite3_stmt* s = db_.statement();
      sqlite3_bind_int64(s, 1, static_cast<std::int64_t>(i + 1));
      sqlite3_bind_text(s, 2, topics[i].name.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(s, 3, topics[i].type.c_str(), -1, SQLITE_TRANSIENT);
      if (db_.Step()) db_.Fail("an insert returned a row");
      sqlite3_reset(s);
    }
    db_.Prepare("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)");
  }

  void Write(size_t topic, std::int64_t log_time_ns, const std::vector<std::uint8_t>& data) override {
    sqlite3_stmt* s = db_.statement();
    sqlite3_bind_int64(s, 1, static_cast<std::int64_t>(topic + 1));
    sqlite3_bind_int64(s, 2, log_time_ns);
    sqlite3_bind_blob64(s, 3, data.data(), data.size(), SQLITE_STATIC);
    if (db_.Step()) db_.Fail("an insert returned a row");
    sqlite3_reset(s);
  }

  void Close() override { db_.Exec("COMMIT"); }

 private:
  static std::string Fresh(const std::string& path) {
    std::error_code ec;
    std::filesystem::remove(path, ec);
    return path;
  }
  Database db_;
};

}  // namespace

std::unique_ptr<MessageReader> OpenSqlite(const std::string& path, const std::set<std::string>& topics) {
  if (!std::filesystem::is_regular_file(path)) throw DatasetError(path + ": no such sqlite3 file");
  return std::make_unique<SqliteReader>(path, topics);
}

std::unique_ptr<MessageFetcher> OpenSqliteFetcher(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw DatasetError(path + ": no such sqlite3 file");
  return std::make_unique<SqliteFetcher>(path);
}

std::unique_ptr<MessageWriter> CreateSqlite(const std::string& path, const std::vector<Topic>& topics) {
  return std::make_unique<SqliteWriter>(path, topics);
}

}  // namespace vio::tools::ros2
