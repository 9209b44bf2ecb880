//! The multibody domain (one test binary): the RATTLE step (`rattle`), ball springs, dampers,
//! equality constraints, the model files, `<include>`, the joint-space reference, merged
//! hinges, the step's symplecticity (`symplectic`), and a UR10e-style wrist (`wrist`).

#[path = "../common/cotangent.rs"]
mod cotangent;
#[path = "../common/model_files.rs"]
mod model_files;
#[path = "../common/thread_counting.rs"]
mod thread_counting;

#[global_allocator]
static GLOBAL: thread_counting::Counting = thread_counting::Counting;

mod actuators;
mod armature;
mod ball_spring;
mod contact;
mod dampers;
mod equality;
mod files;
mod friction;
mod include;
mod joint_space;
mod merged;
mod rattle;
mod symplectic;
mod wrist;
