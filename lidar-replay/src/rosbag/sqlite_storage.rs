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
