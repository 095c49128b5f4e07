//! The picture of the system that `rig run` records on `/scene` ([`scene`], a
//! [`runtime::record::scene::SceneMaker`]): the pendulum, the two-link arm or, for a
//! system the rig does not simulate, a bar per state component — a Foxglove
//! `SceneUpdate` drawn from a state, protobuf-encoded by the official `foxglove` crate.
//! Every picture fits a 1 m radius around the origin (the arms' reach scaled to it), so
//! one camera of the layout shows each.

use foxglove::Encode;
use foxglove::schemas::{
    Color, CubePrimitive, LinePrimitive, Point3, Pose, SceneEntity, SceneUpdate, SpherePrimitive,
    Timestamp, Vector3, line_primitive,
};
use plant::task::{SystemName, Task};
use runtime::record::scene::{Encoding, Scene};

/// The frame the picture is drawn in.
pub const FRAME: &str = "world";

/// What is drawn, and how, for a task's system.
#[derive(Clone, Debug, PartialEq)]
pub enum Body {
    /// One link turning about the origin in the vertical plane, `φ = x₀` from upright.
    Pendulum,
    /// Two links, `φ₁ = x₀` and `φ₂ = x₁` relative to the first, of these lengths
    /// (scaled to a reach of 1); in the vertical plane hanging down at zero, or seen
    /// from above in the horizontal plane.
    Arm {
        /// The links' lengths, summing to 1.
        lengths: [f64; 2],
        /// The vertical plane (Case I), or the horizontal one.
        vertical: bool,
    },
    /// A bar per state component, its height the component's place in the task's
    /// state range, from −1 (its low end) to 1 (its high end).
    Bars {
        /// Per component, `(low, high)`.
        ranges: Vec<(f64, f64)>,
    },
}

impl Body {
    /// The picture of `task`'s system.
    pub fn of(task: &Task) -> Body {
        let system = task.simulation.as_ref().map(|s| s.system);
        let arm = |l: [f64; 2], vertical| Body::Arm {
            lengths: l.map(|x| x / (l[0] + l[1])),
            vertical,
        };
        match system {
            Some(SystemName::Pendulum) => Body::Pendulum,
            Some(SystemName::ArmVertical) => arm(plant::two_link::TwoLink::vertical().length, true),
            Some(SystemName::ArmHorizontal) => {
                arm(plant::two_link::TwoLink::horizontal().length, false)
            }
            Some(SystemName::Arm64) => {
                arm(plant::two_link::TwoLink::manipulator_6_4().length, false)
            }
            Some(SystemName::DoubleIntegrator) | None => Body::Bars {
                ranges: task.state_range.clone(),
            },
        }
    }

    /// The scene of state `x` at log time `t_ns`: one entity, `system`, replacing the last.
    pub fn draw(&self, x: &[f64], t_ns: u64) -> SceneUpdate {
        let at = |x: f64, y: f64, z: f64| Point3 { x, y, z };
        let mut entity = SceneEntity {
            timestamp: Some(timestamp(t_ns)),
            frame_id: FRAME.to_string(),
            id: "system".to_string(),
            ..Default::default()
        };
        let angle = |i: usize| x.get(i).copied().filter(|v| v.is_finite()).unwrap_or(0.0);
        match self {
            Body::Pendulum => {
                let phi = angle(0);
                links(
                    &mut entity,
                    &[at(0.0, 0.0, 0.0), at(phi.sin(), 0.0, phi.cos())],
                );
            }
            Body::Arm { lengths, vertical } => {
                let (p1, p2) = (angle(0), angle(1));
                let [l1, l2] = *lengths;
                // Vertical: x across, z up, zero hanging down. Horizontal: seen from above.
                let point = |a: f64, b: f64| match vertical {
                    true => at(a, 0.0, b),
                    false => at(a, b, 0.0),
                };
                type Axis = fn(f64) -> f64;
                let (c, s): (Axis, Axis) = match vertical {
                    true => (f64::sin, |t| -t.cos()),
                    false => (f64::cos, f64::sin),
                };
                let elbow = (l1 * c(p1), l1 * s(p1));
                let tip = (elbow.0 + l2 * c(p1 + p2), elbow.1 + l2 * s(p1 + p2));
                links(
                    &mut entity,
                    &[
                        point(0.0, 0.0),
                        point(elbow.0, elbow.1),
                        point(tip.0, tip.1),
                    ],
                );
            }
            Body::Bars { ranges } => bars(&mut entity, ranges, x),
        }
        SceneUpdate {
            deletions: Vec::new(),
            entities: vec![entity],
        }
    }
}

/// The pictures of a task's system, for the recording's `/scene`.
struct Pictures(Body);

impl Scene for Pictures {
    fn encoding(&self) -> Encoding {
        let schema = SceneUpdate::get_schema().expect("a Foxglove schema has its descriptor");
        Encoding {
            schema_name: schema.name,
            schema_encoding: schema.encoding,
            schema: schema.data.into_owned(),
            message_encoding: SceneUpdate::get_message_encoding(),
        }
    }

    fn draw(&mut self, x: &[f64], t_ns: u64, out: &mut Vec<u8>) {
        out.clear();
        self.0
            .draw(x, t_ns)
            .encode(out)
            .expect("a growing buffer holds any message");
    }
}

/// The `/scene` of `task`'s system (`runtime::run::RunOptions::scene`).
pub fn scene(task: &Task) -> Box<dyn Scene> {
    Box::new(Pictures(Body::of(task)))
}

/// Links through `joints`, a ball at each joint.
fn links(entity: &mut SceneEntity, joints: &[Point3]) {
    entity.lines.push(LinePrimitive {
        r#type: line_primitive::Type::LineStrip as i32,
        thickness: 0.05,
        points: joints.to_vec(),
        color: Some(color(0.2, 0.5, 0.9)),
        ..Default::default()
    });
    for &p in joints {
        entity.spheres.push(SpherePrimitive {
            pose: Some(pose(p)),
            size: Some(Vector3 {
                x: 0.1,
                y: 0.1,
                z: 0.1,
            }),
            color: Some(color(0.9, 0.4, 0.1)),
        });
    }
}

/// A bar per component of `x` along the x axis, its height from −1 to 1 over the
/// component's range; a component not finite draws no bar.
fn bars(entity: &mut SceneEntity, ranges: &[(f64, f64)], x: &[f64]) {
    let n = ranges.len().max(1) as f64;
    for (i, (&(low, high), &v)) in ranges.iter().zip(x).enumerate() {
        let h = (2.0 * (v - low) / (high - low) - 1.0).clamp(-1.0, 1.0);
        if !h.is_finite() {
            continue;
        }
        let across = -1.0 + (2.0 * i as f64 + 1.0) / n;
        entity.cubes.push(CubePrimitive {
            pose: Some(pose(Point3 {
                x: across,
                y: 0.0,
                z: h / 2.0,
            })),
            size: Some(Vector3 {
                x: 1.6 / n,
                y: 0.1,
                z: h.abs().max(0.01),
            }),
            color: Some(color(0.2, 0.5, 0.9)),
        });
    }
}

fn pose(position: Point3) -> Pose {
    Pose {
        position: Some(Vector3 {
            x: position.x,
            y: position.y,
            z: position.z,
        }),
        orientation: None,
    }
}

fn color(r: f64, g: f64, b: f64) -> Color {
    Color { r, g, b, a: 1.0 }
}

fn timestamp(t_ns: u64) -> Timestamp {
    Timestamp::new((t_ns / 1_000_000_000) as u32, (t_ns % 1_000_000_000) as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(u: &SceneUpdate) -> Vec<(f64, f64, f64)> {
        u.entities[0].lines[0]
            .points
            .iter()
            .map(|p| (p.x, p.y, p.z))
            .collect()
    }

    fn close(a: (f64, f64, f64), b: (f64, f64, f64)) -> bool {
        (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12 && (a.2 - b.2).abs() < 1e-12
    }

    #[test]
    fn the_pendulum_stands_upright_at_zero_and_hangs_down_at_pi() {
        let up = Body::Pendulum.draw(&[0.0, 0.0], 0);
        assert!(close(points(&up)[1], (0.0, 0.0, 1.0)));
        let down = Body::Pendulum.draw(&[std::f64::consts::PI, 0.0], 0);
        assert!(close(points(&down)[1], (0.0, 0.0, -1.0)));
        assert_eq!(up.entities[0].spheres.len(), 2);
    }

    #[test]
    fn the_arm_bends_at_its_elbow_by_the_second_angle() {
        let arm = Body::Arm {
            lengths: [0.5, 0.5],
            vertical: false,
        };
        let half_pi = std::f64::consts::FRAC_PI_2;
        let p = points(&arm.draw(&[0.0, half_pi, 0.0, 0.0], 0));
        assert!(close(p[1], (0.5, 0.0, 0.0)), "{p:?}");
        assert!(close(p[2], (0.5, 0.5, 0.0)), "{p:?}");
        let hanging = Body::Arm {
            lengths: [0.5, 0.5],
            vertical: true,
        };
        let p = points(&hanging.draw(&[0.0, 0.0, 0.0, 0.0], 0));
        assert!(close(p[2], (0.0, 0.0, -1.0)), "{p:?}");
    }

    #[test]
    fn a_recorded_picture_is_the_scene_update_protobuf_encoded() {
        use foxglove::Decode;
        let mut pictures = scene(&Task::pendulum());
        assert_eq!(pictures.encoding().schema_name, "foxglove.SceneUpdate");
        assert_eq!(pictures.encoding().message_encoding, "protobuf");
        let mut out = vec![1, 2, 3];
        pictures.draw(&[std::f64::consts::PI, f64::NAN], 5, &mut out);
        let back = SceneUpdate::decode(&out[..]).unwrap();
        assert_eq!(back, Body::Pendulum.draw(&[std::f64::consts::PI, 0.0], 5));
    }

    #[test]
    fn a_bar_shows_where_its_component_is_in_the_range_and_a_nan_draws_none() {
        let bars = Body::Bars {
            ranges: vec![(-2.0, 2.0), (0.0, 1.0), (0.0, 1.0)],
        };
        let u = bars.draw(&[2.0, 0.25, f64::NAN], 7_000_000_001);
        let cubes = &u.entities[0].cubes;
        assert_eq!(cubes.len(), 2);
        assert_eq!(cubes[0].size.unwrap().z, 1.0);
        assert_eq!(cubes[1].pose.unwrap().position.unwrap().z, -0.25);
        let t = u.entities[0].timestamp.unwrap();
        assert_eq!((t.sec(), t.nsec()), (7, 1));
    }
}
