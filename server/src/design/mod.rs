//! Designs at run time: one actor task per design holding its kernel state
//! ([`actor`]), the commands it runs ([`command`]), undo/redo ([`undo`]),
//! the document it persists and the kernel model it drives ([`model`]), and
//! the registry of running actors ([`hub`]).

pub mod actor;
pub mod body_demo;
pub mod body_engine;
pub mod body_part;
pub mod body_proof;
pub mod command;
pub mod comment_write;
pub mod comments;
pub mod commit_write;
pub mod curve_engine;
pub mod deflated_frame;
pub mod demo;
pub mod doc;
pub mod drag_stream;
pub mod dsm_delta;
pub mod dsm_engine;
pub mod edit;
pub mod engine;
pub mod error;
pub mod exchange;
pub mod fairing_job;
pub mod ffd_binding;
pub mod ffd_frame;
pub mod hub;
pub mod legacy;
pub mod model;
pub mod morph_follow;
pub mod network_demo;
pub mod network_engine;
pub mod part;
pub mod product_engine;
pub mod spring_band;
pub mod undo;

pub use actor::{ClientInfo, DesignEvent, DesignHandle, Joined, Presence};
pub use command::{Ack, Command};
pub use error::{CommandError, ErrorKind};
pub use hub::Hub;
pub use model::{Created, DesignDoc, DesignModel, Edit, MaterialEdit, PartEdit};
