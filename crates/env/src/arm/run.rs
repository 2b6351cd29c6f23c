//! One episode to files.
