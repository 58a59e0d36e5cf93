//! The path tracer's checkpoint loader on arbitrary bytes: it must return a checkpoint whose
//! parts fit, or an error naming the file, and never panic. A checkpoint that loads is then
//! matched against a task's defaults (the check `--resume` runs next), which must not panic
//! either.

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use pathtracer::run::{Checkpoint, Settings};
use pathtracer::tasks;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz/checkpoint.json");
    match Checkpoint::parse_any_build(data, path) {
        Ok(c) => {
            if let Some(task) = tasks::by_name(&c.task) {
                let _ = c.check_matches(&task, &Settings::defaults(&task), path);
            }
        }
        Err(e) => assert!(e.to_string().contains("fuzz/checkpoint.json")),
    }
});
