//! Which candidates a campaign draws and in what order it flies them: the draws of each round (histogram
//! and children near failures), the diversity guard, the ranking, and the rounds themselves.

pub mod diversity_guard;
pub mod draw;
pub mod expected_points;
pub mod judged_mean;
pub mod neighbours;
pub mod rank;
pub mod rounds;
