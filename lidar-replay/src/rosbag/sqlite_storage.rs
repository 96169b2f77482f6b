//! The SQLite3 storage of rosbag2 (`.db3`): a `topics` table (id, name, type,
//! serialization_format, ...) and a `messages` table (id, topic_id, timestamp, data),
//! read in timestamp order a page at a time, so memory stays bounded by a page.

use std::collections::{HashMap, VecDeque};
use std::path::Path;
use std::sync::Arc;

use rusqlite::{Connection, OpenFlags};

use super::storage::{Channel, Damaged, MessageSource, RawMessage};

/// Messages fetched from the database at a time.
const PAGE: i64 = 256;

/// Why a database is no rosbag2 storage.
#[derive(Debug, thiserror::Error)]
#[error("{path} is not a rosbag2 SQLite3 storage: {cause}")]
pub struct SqliteError {
    pub path: String,
    pub cause: String,
}

/// The messages of a `.db3` file in timestamp order.
pub struct SqliteSource {
    connection: Connection,
    channels: HashMap<i64, Arc<Channel>>,
    /// (timestamp, id) of the last message fetched.
    last: Option<(i64, i64)>,
    page: VecDeque<RawMessage>,
    /// Why the database cannot be read on, told once the page before it is given out.
    damage: Option<Damaged>,
    ended: bool,
}

impl SqliteSource {
    /// Opens `path` read-only and reads its topics.
    pub fn open(path: &Path) -> Result<Self, SqliteError> {
        let error = |cause: rusqlite::Error| SqliteError {
            path: path.display().to_string(),
            cause: cause.to_string(),
        };
        let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let connection = Connection::open_with_flags(path, flags).map_err(error)?;
        let channels = topics(&connection).map_err(error)?;
        Ok(Self {
            connection,
            channels,
            last: None,
            page: VecDeque::new(),
            damage: None,
            ended: false,
        })
    }

    /// The topics the database declares, in the order of their ids.
    pub fn channels(&self) -> Vec<Channel> {
        let mut channels: Vec<(&i64, &Arc<Channel>)> = self.channels.iter().collect();
        channels.sort_by_key(|(id, _)| **id);
        channels
            .into_iter()
            .map(|(_, channel)| (**channel).clone())
            .collect()
    }

    fn fetch(&mut self) -> Result<(), rusqlite::Error> {
        let (after_time, after_id) = self.last.unwrap_or((i64::MIN, i64::MIN));
        let mut statement = self.connection.prepare_cached(
            "SELECT id, topic_id, timestamp, data FROM messages \
             WHERE timestamp >= ?1 AND (timestamp > ?1 OR id > ?2) \
             ORDER BY timestamp, id LIMIT ?3",
        )?;
        let mut rows = statement.query((after_time, after_id, PAGE))?;
        while let Some(row) = rows.next()? {
            let id: i64 = row.get(0)?;
            let topic_id: i64 = row.get(1)?;
            let timestamp: i64 = row.get(2)?;
            let data: Vec<u8> = row.get(3)?;
            self.last = Some((timestamp, id));
            let channel = self.channels.get(&topic_id).cloned().unwrap_or_else(|| {
                // A message of no declared topic: it is passed over under this name.
                Arc::new(Channel {
                    topic: format!("(topic id {topic_id})"),
                    type_name: String::new(),
                    encoding: String::new(),
                })
            });
            self.page.push_back(RawMessage {
                channel,
                log_time_ns: u64::try_from(timestamp).unwrap_or(0),
                data,
            });
        }
        Ok(())
    }
}

fn topics(connection: &Connection) -> Result<HashMap<i64, Arc<Channel>>, rusqlite::Error> {
    let mut statement =
        connection.prepare("SELECT id, name, type, serialization_format FROM topics")?;
    let rows = statement.query_map((), |row| {
        Ok((
            row.get::<_, i64>(0)?,
            Channel {
                topic: row.get(1)?,
                type_name: row.get(2)?,
                encoding: row.get(3)?,
            },
        ))
    })?;
    rows.map(|row| row.map(|(id, channel)| (id, Arc::new(channel))))
        .collect()
}

impl MessageSource for SqliteSource {
    fn next_message(&mut self) -> Option<Result<RawMessage, Damaged>> {
        if self.page.is_empty() && !self.ended {
            if let Err(e) = self.fetch() {
                self.damage = Some(Damaged(e.to_string()));
            }
            // A page shorter than asked for is the last; a damaged one is too.
            if self.page.len() < PAGE as usize || self.damage.is_some() {
                self.ended = true;
            }
        }
        match self.page.pop_front() {
            Some(message) => Some(Ok(message)),
            None => self.damage.take().map(Err),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("lidar-replay-sqlite-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A rosbag2 database: two topics, and `messages` (topic id, timestamp) with their
    /// number as data.
    fn database(path: &Path, messages: &[(i64, i64)]) {
        let db = Connection::open(path).unwrap();
        db.execute_batch(
            "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, \
             serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
             CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, \
             timestamp INTEGER NOT NULL, data BLOB NOT NULL);
             CREATE INDEX timestamp_idx ON messages (timestamp ASC);
             INSERT INTO topics VALUES (1, '/scan', 'sensor_msgs/msg/LaserScan', 'cdr', '');
             INSERT INTO topics VALUES (2, '/odom', 'nav_msgs/msg/Odometry', 'cdr', '');",
        )
        .unwrap();
        // One transaction: a commit a row would sync the disk 700 times.
        db.execute_batch("BEGIN").unwrap();
        for (n, (topic, time)) in messages.iter().enumerate() {
            db.execute(
                "INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)",
                (topic, time, (n as u32).to_le_bytes().to_vec()),
            )
            .unwrap();
        }
        db.execute_batch("COMMIT").unwrap();
    }

    #[test]
    fn messages_come_in_time_order_across_pages_of_equal_times() {
        let dir = scratch("pages");
        let path = dir.join("bag_0.db3");
        // Three messages a time, times going back every 100 rows, a topic no table names.
        let messages: Vec<(i64, i64)> = (0..700)
            .map(|n: i64| (if n == 5 { 9 } else { 1 + n % 2 }, (n / 3) % 100))
            .collect();
        database(&path, &messages);
        let mut source = SqliteSource::open(&path).unwrap();
        assert_eq!(source.channels().len(), 2);
        assert_eq!(source.channels()[1].topic, "/odom");
        let read: Vec<RawMessage> = std::iter::from_fn(|| source.next_message())
            .map(Result::unwrap)
            .collect();
        assert_eq!(read.len(), 700);
        let keys: Vec<(u64, u32)> = read
            .iter()
            .map(|m| {
                let n = u32::from_le_bytes(m.data[..4].try_into().unwrap());
                (m.log_time_ns, n)
            })
            .collect();
        let mut sorted = keys.clone();
        sorted.sort();
        assert_eq!(keys, sorted, "by time, then as written");
        assert_eq!(read[0].channel.topic, "/scan");
        assert!(read.iter().any(|m| m.channel.topic == "(topic id 9)"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_file_that_is_no_database_is_refused_by_name() {
        let dir = scratch("foreign");
        let path = dir.join("bag_0.db3");
        std::fs::write(&path, "FLASER 180 ...\n".repeat(200)).unwrap();
        let error = SqliteSource::open(&path)
            .err()
            .expect("refused")
            .to_string();
        assert!(
            error.starts_with(&format!(
                "{} is not a rosbag2 SQLite3 storage: ",
                path.display()
            )),
            "{error}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
