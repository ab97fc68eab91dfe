//! rosbag2's `metadata.yaml` (version 5, what ROS 2 Humble writes and every later reader
//! takes) and the QoS profiles it and the MCAP channels offer.

use super::Counts;

/// What a finished bag holds.
pub struct Summary {
    pub counts: Counts,
    /// The first and last message's time stamp (nanoseconds).
    pub span: (u64, u64),
    pub file: &'static str,
}

/// The QoS profile a topic was offered with, as rosbag2 writes it (a YAML list in a string;
/// rmw's numbers: history 1 keep-last, reliability 1 reliable, durability 1 transient-local or
/// 2 volatile, liveliness 1 automatic; zero durations are the defaults). Transient-local is
/// what lets `ros2 bag play` deliver `/tf_static` to a node that starts later.
pub fn qos(latched: bool) -> String {
    let durability = if latched { 1 } else { 2 };
    let zero = "\n    sec: 0\n    nsec: 0";
    format!(
        "- history: 1\n  depth: {}\n  reliability: 1\n  durability: {durability}\n  \
         deadline:{zero}\n  lifespan:{zero}\n  liveliness: 1\n  \
         liveliness_lease_duration:{zero}\n  avoid_ros_namespace_conventions: false",
        if latched { 1 } else { 10 }
    )
}

/// A string as a YAML double-quoted scalar.
fn quoted(s: &str) -> String {
    serde_json::to_string(s).expect("a string serialises")
}

/// The folder's `metadata.yaml` for a bag of one file holding `summary`.
pub fn metadata(summary: &Summary) -> String {
    let (start, end) = summary.span;
    let messages: u64 = summary.counts.values().map(|c| c.1).sum();
    let duration = end - start;
    let mut y = String::from("rosbag2_bagfile_information:\n  version: 5\n");
    y.push_str("  storage_identifier: mcap\n");
    y.push_str(&format!(
        "  duration:\n    nanoseconds: {duration}\n  starting_time:\n    \
         nanoseconds_since_epoch: {start}\n  message_count: {messages}\n"
    ));
    y.push_str("  topics_with_message_count:\n");
    for (topic, (msg_type, count, latched)) in &summary.counts {
        y.push_str(&format!(
            "    - topic_metadata:\n        name: {}\n        type: {}\n        \
             serialization_format: cdr\n        offered_qos_profiles: {}\n      \
             message_count: {count}\n",
            quoted(topic),
            quoted(msg_type),
            quoted(&qos(*latched)),
        ));
    }
    y.push_str("  compression_format: \"\"\n  compression_mode: \"\"\n");
    y.push_str(&format!(
        "  relative_file_paths:\n    - {file}\n  files:\n    - path: {file}\n      \
         starting_time:\n        nanoseconds_since_epoch: {start}\n      duration:\n        \
         nanoseconds: {duration}\n      message_count: {messages}\n",
        file = quoted(summary.file),
    ));
    y
}
