//! File helpers for the layers above the model. The atomic writer lives in the model (its errors are
//! [`crate::model::ModelError`]s, and the model writes tests with it); this path keeps it at hand for the rest.

pub use crate::model::write_atomic;
