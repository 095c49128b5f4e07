//! `rigkit`'s recording reader (python/rigkit/recording.py) names run.mcap's topics and
//! the messages' flags as the rig writes them: every topic and flag it defines is the
//! one of the same name in `runtime::record::channels` and `wire::flags`.

use runtime::record::channels;
use wire::flags;

/// The module-level constants `NAME = value` of the reader, in file order.
fn constants() -> Vec<(String, String)> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../python/rigkit/recording.py");
    let text = std::fs::read_to_string(path).expect("the reader's source");
    text.lines()
        .filter_map(|line| line.split_once(" = "))
        .filter(|(name, _)| {
            !name.is_empty()
                && name
                    .chars()
                    .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
        })
        .map(|(name, value)| (name.to_string(), value.trim().to_string()))
        .collect()
}

#[test]
fn the_python_reader_names_the_topics_and_flags_of_the_rig() {
    let topics = [
        ("MEASUREMENT", channels::MEASUREMENT),
        ("ESTIMATE", channels::ESTIMATE),
        ("ACTION", channels::ACTION),
        ("TRUTH", channels::TRUTH),
        ("PLANT_TIMING", channels::TIMING[0]),
        ("OBSERVER_TIMING", channels::TIMING[1]),
        ("AGENT_TIMING", channels::TIMING[2]),
        ("DRIVER_SAMPLE", channels::DRIVER_SAMPLE),
        ("DRIVER_COMMAND", channels::DRIVER_COMMAND),
        ("DRIVER_LINK", channels::DRIVER_LINK),
        ("RETURNS", channels::RETURNS),
        ("LATENCY", channels::LATENCY),
        ("SCENE", channels::SCENE),
    ];
    let bits = [
        ("START", flags::START),
        ("END", flags::END),
        ("GREEDY", flags::GREEDY),
        ("SHUTDOWN", flags::SHUTDOWN),
        ("TERMINAL", flags::TERMINAL),
        ("LAST", flags::LAST),
        ("HOLD", flags::HOLD),
        ("PRIMED", flags::PRIMED),
        ("ESTIMATED_REWARD", flags::ESTIMATED_REWARD),
        ("GAP", flags::GAP),
        ("DRIVER_REWARD", flags::DRIVER_REWARD),
    ];
    let (mut n_topics, mut n_bits) = (0, 0);
    for (name, value) in constants() {
        if let Some(topic) = value.strip_prefix('"').and_then(|v| v.strip_suffix('"')) {
            let Some((_, rig)) = topics.iter().find(|(n, _)| *n == name) else {
                panic!("recording.py's topic {name} = {value} is no channel of the rig's");
            };
            assert_eq!(topic, *rig, "recording.py's {name}");
            n_topics += 1;
        } else if let Ok(bit) = value.parse::<u64>() {
            let Some((_, rig)) = bits.iter().find(|(n, _)| *n == name) else {
                panic!("recording.py's flag {name} = {value} is no flag of the rig's");
            };
            assert_eq!(bit, *rig, "recording.py's {name}");
            n_bits += 1;
        }
    }
    // What the reader uses today: seven topics and nine flags.
    assert!(
        n_topics >= 7 && n_bits >= 9,
        "{n_topics} topics, {n_bits} flags"
    );
}
