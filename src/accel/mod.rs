//! Acceleration structures and ray/primitive intersection.
