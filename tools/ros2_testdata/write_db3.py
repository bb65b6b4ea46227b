#!/usr/bin/env python3
"""Writes the messages write_bag.js --format=jsonl gave (CDR from Foxglove's serializer) as a
rosbag2 sqlite3 bag folder with python3's sqlite3 module: an independent writer for vio's tests.

usage: write_db3.py JSONL FOLDER [--files=N] [--layout=humble|jazzy]
The messages are split into N .db3 files (each with its own topics table, ids in another order
per file) listed by metadata.yaml. humble: the topics and messages tables of ROS 2 Humble and
before; jazzy: also its schema, metadata and message_definitions tables and the
type_description_hash column.
"""
import argparse
import base64
import json
import os
import sqlite3

TOPICS = {
    "humble": "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
              "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL)",
    "jazzy": "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
             "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL, "
             "type_description_hash TEXT NOT NULL)",
}
JAZZY_EXTRA = [
    "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL)",
    "INSERT INTO schema VALUES (4, 'jazzy')",
    "CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL)",
    "CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL, encoding TEXT NOT NULL, "
    "encoded_message_definition TEXT NOT NULL, type_description_hash TEXT NOT NULL)",
]


def write_file(path, messages, layout, reverse_ids):
    if os.path.exists(path):
        os.remove(path)
    db = sqlite3.connect(path)
    db.execute(TOPICS[layout])
    db.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
               "timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
    db.execute("CREATE INDEX timestamp_idx ON messages (timestamp ASC)")
    for sql in JAZZY_EXTRA if layout == "jazzy" else []:
        db.execute(sql)
    names = sorted({(m["topic"], m["type"]) for m in messages}, reverse=reverse_ids)
    ids = {}
    for i, (name, type_) in enumerate(names):
        ids[name] = 10 * (i + 1)
        extra = ", ''" if layout == "jazzy" else ""
        db.execute(f"INSERT INTO topics VALUES (?, ?, ?, 'cdr', ''{extra})", (ids[name], name, type_))
    db.executemany("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)",
                   ((ids[m["topic"]], int(m["t"]), base64.b64decode(m["cdr"])) for m in messages))
    db.commit()
    db.close()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("jsonl")
    parser.add_argument("folder")
    parser.add_argument("--files", type=int, default=1)
    parser.add_argument("--layout", choices=["humble", "jazzy"], default="humble")
    args = parser.parse_args()
    with open(args.jsonl) as f:
        messages = [json.loads(line) for line in f]
    os.makedirs(args.folder, exist_ok=True)
    name = os.path.basename(os.path.normpath(args.folder))
    per_file = (len(messages) + args.files - 1) // args.files
    files = []
    for k in range(args.files):
        files.append(f"{name}_{k}.db3")
        write_file(os.path.join(args.folder, files[-1]), messages[k * per_file:(k + 1) * per_file], args.layout,
                   reverse_ids=k % 2 == 1)
    with open(os.path.join(args.folder, "metadata.yaml"), "w") as f:
        f.write("rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
                f"  message_count: {len(messages)}\n  compression_format: \"\"\n  compression_mode: \"\"\n"
                "  relative_file_paths:\n" + "".join(f"    - {file}\n" for file in files))


if __name__ == "__main__":
    main()
