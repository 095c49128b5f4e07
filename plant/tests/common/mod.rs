//! What the task file tests share: files of their own, and the check that a bad file is
//! refused in one line naming the file.
#![allow(dead_code)]

use std::path::PathBuf;

use plant::Task;

/// `text` written to `name` in a folder of `suite`'s own.
pub fn write(suite: &str, name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rig-{suite}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Each `(what, text, want)`: the task file `text` is refused in one line that names the
/// file and contains `want`.
pub fn assert_refused(suite: &str, cases: &[(&str, String, &str)]) {
    for (what, text, want) in cases {
        let path = write(suite, "bad.toml", text);
        let e = match Task::from_file(&path) {
            Ok(_) => panic!("{what}: accepted"),
            Err(e) => e.to_string(),
        };
        assert!(!e.contains('\n'), "{what}: one line: {e}");
        assert!(
            e.starts_with(&format!("{}: ", path.display())),
            "{what}: names the file: {e}"
        );
        assert!(e.contains(want), "{what}: {e}\n  should contain: {want}");
    }
}
