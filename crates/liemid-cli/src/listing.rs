//! `liemid problems` and `liemid methods`: the built-in problems and the methods of all
//! five domains, each under the subcommand and option that takes them.

use liemid::beam::BeamIntegrator;
use liemid::multibody::MultibodyMethod;

use crate::many::scenario::{Model, Rotation};
use crate::{multibody, rigid};

/// The built-in problems of every domain.
pub fn problems() {
    outln!("liemid run --problem NAME:");
    for name in rigid::scenario::PROBLEMS {
        outln!("{name:<22} {}", rigid::scenario::describe(name));
    }
    outln!("{:<22} {}", rigid::satellite::PROBLEM, rigid::satellite::DESCRIPTION);
    outln!("\nliemid many --model NAME:");
    for model in Model::ALL {
        outln!("{:<22} {}", model.key(), model.description());
    }
    outln!("\nliemid spins --problem NAME:");
    for name in liemid::spin::problems::NAMES {
        outln!("{name:<22} {}", liemid::spin::problems::describe(name).unwrap_or(""));
    }
    outln!("\nliemid beam --problem NAME:");
    for name in liemid::beam::problems::NAMES {
        let description = liemid::beam::problems::by_name(name, None).map(|p| p.description);
        outln!("{name:<22} {}", description.unwrap_or(""));
    }
    outln!("\nliemid multibody --problem NAME:");
    for name in multibody::scenario::PROBLEMS {
        outln!("{name:<22} {}", multibody::scenario::describe(name));
    }
}

/// The methods of every domain (the rigid body's table first, as before the other
/// domains had methods), or with `spins` only the spin table (`json`: as JSON).
pub fn methods(spins: bool, json: bool) {
    if spins {
        crate::spin::command::methods(json);
        return;
    }
    outln!("liemid run --method NAME:");
    rigid::command::methods();
    outln!("\nliemid many --rotation NAME:");
    for rotation in Rotation::ALL {
        outln!("{:<11} {}", rotation.key(), rotation.description());
    }
    outln!("\nliemid spins --method NAME:");
    crate::spin::command::methods(false);
    outln!("\nliemid beam --method NAME:");
    outln!("{:<11} {:>5}  {:<22} what it is", "name", "order", "force evals/step");
    for integrator in BeamIntegrator::ALL {
        let (order, evaluations, what) = match integrator {
            BeamIntegrator::Explicit(m) => (m.order(), m.evaluations_per_step().to_string(), m.description()),
            BeamIntegrator::Newmark => (
                2,
                "1 per Newton iteration".into(),
                "implicit Newmark, average acceleration (gamma = 1/2, beta = 1/4), Newton on the exact tangent",
            ),
        };
        outln!("{:<11} {order:>5}  {evaluations:<22} {what}", integrator.key());
    }
    outln!("\nliemid beam --drift NAME and liemid multibody --drift NAME (the liemid methods' rotation):");
    for drift in liemid::variational::Drift::ALL {
        let what = match drift {
            liemid::variational::Drift::Midpoint => {
                "two midpoint half steps, as in liemid-ea (the default; not symplectic, O(h^3) Lie-Poisson defect)"
            }
            liemid::variational::Drift::Variational => {
                "two variational half steps, as in liemid-eav (a Lie-Poisson drift; measured symplectic: the beam methods, a free multibody body)"
            }
        };
        outln!("{:<11} {what}", drift.key());
    }
    outln!("\nliemid multibody --method NAME:");
    outln!("{:<11} {:>5}  what it is", "name", "order");
    for m in MultibodyMethod::ALL {
        outln!("{:<11} {:>5}  {}", m.key(), m.order(), m.description());
    }
    outln!(
        "{:<11} {:>5}  classical RK4 in joint coordinates (articulated-body algorithm); the reference",
        "rk4",
        4
    );
    outln!(
        "{:<11} {:>5}  Dormand-Prince 8(5,3) with step control in joint coordinates (--rtol); the reference",
        "dop853",
        8
    );
}
