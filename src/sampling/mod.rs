//! Deterministic sampling: pixel patterns and light samples.
