//! Which candidates a campaign draws and in what order it flies them: the draws of each round (histogram
//! and children near failures), the diversity guard and the ranking; the rounds themselves are conducted by
//! [`crate::campaign::conductor`].

pub mod diversity_guard;
pub mod draw;
pub mod neighbours;
pub mod rank;
