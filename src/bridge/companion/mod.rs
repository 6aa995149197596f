//! Planning while flying: the avoidance companion (PX4's TRAJECTORY_REPRESENTATION_WAYPOINTS interface) and the
//! offboard pilot, both steered by the LFS planner over the virtual boxes in the test's frame, and the LFS
//! prediction reported beside the flight. Talks to the vehicle only through [`super::wire`].

pub mod answers;
pub mod avoidance;
pub mod cp_feed;
pub mod frame;
pub mod offboard;
pub mod pacing;
pub mod planner_steer;
mod pose_history;
pub mod predict;
pub mod sim_paced;
pub mod steer;
pub mod steer_worker;
pub mod timing;
mod trajectory_points;
