//! The animation systems: keyframed objects, camera and emission set for the frame's shutter,
//! media read from the frame's files.

use super::components::{
    Animated, CameraKeys, CameraParams, EmitKeys, Filling, FrameErrors, FrameNumber, FrameTime, GridInputs,
    GridReads, GridSequence, Materials, Motion, ObjectIndex, Transform,
};
use crate::scene::{CameraDesc, CameraView};
use bevy_ecs::prelude::*;
use glam::{Affine3A, Vec3, Vec3A};

/// Places keyframed objects for the frame's shutter: rotation and scale as at mid-shutter,
/// translation moving linearly from its position at shutter open to the one at shutter close
/// (as a [`Motion`], so rays see it at their own time). Components are written only when they
/// change, so a frame that moves nothing rebuilds nothing.
pub fn animate_objects(
    time: Res<FrameTime>,
    mut objects: Query<(Ref<Animated>, &mut Transform, &mut Motion)>,
) {
    for (anim, mut transform, mut motion) in &mut objects {
        if !(time.is_changed() || anim.is_changed()) {
            continue;
        }
        let at = |t: f32| anim.keys.at(t) * anim.base;
        let (t0, t1) = (time.open, time.close);
        let mid = at(0.5 * (t0 + t1));
        let (p0, p1) = (at(t0).translation, at(t1).translation);
        let v = if t1 > t0 { (p1 - p0) / (t1 - t0) } else { Vec3A::ZERO };
        // At time t the object is at p0 + v (t - t0) (plus its own motion, v_own t).
        let placed = Affine3A { matrix3: mid.matrix3, translation: p0 - v * t0 };
        let velocity = Vec3::from(v) + anim.velocity;
        transform.set_if_neq(Transform(placed));
        motion.set_if_neq(Motion { velocity });
    }
}

/// Sets the camera for the frame: keyframes at mid-shutter, shutter = the frame's.
pub fn animate_camera(
    time: Res<FrameTime>,
    keys: Res<CameraKeys>,
    mut camera: ResMut<CameraParams>,
    mut errors: ResMut<FrameErrors>,
) {
    if !(time.is_changed() || keys.is_changed()) {
        return;
    }
    let at = |t: f32| {
        let mut c = keys.base;
        let k = &keys.keys;
        // The loader refuses look_from, look_at and vfov keys for a `to_world` camera.
        let mut target = None;
        if let CameraView::LookAt { look_from, look_at, vfov, .. } = &mut c.view {
            if let Some(k) = &k.look_from {
                *look_from = k.at(t);
            }
            if let Some(k) = &k.look_at {
                *look_at = k.at(t);
            }
            if let Some(k) = &k.vfov {
                *vfov = k.at(t);
            }
            target = Some(*look_at - *look_from);
        }
        if let Some(k) = &k.focus_dist {
            c.focus_dist = k.at(t);
        } else if let Some(view) = target.filter(|_| k.look_from.is_some() || k.look_at.is_some()) {
            // The default focus distance follows the target.
            c.focus_dist = view.length();
        }
        c.shutter = (time.open, time.close);
        c
    };
    // A camera that moves while the shutter is open: its poses at open and close, between
    // which camera rays interpolate.
    let (open, close) = (at(time.open), at(time.close));
    // The keys may carry the camera where the loader would refuse it (look_from onto look_at,
    // vup along the view, a vfov or focus_dist through zero): the frame reports it.
    for (t, c) in [(time.open, &open), (time.close, &close)] {
        if let Err(e) = c.check() {
            errors.0.push(format!("animation: at time {t}, {e}"));
            return;
        }
    }
    let next = if same_camera(&open, &close) {
        (at(0.5 * (time.open + time.close)), None)
    } else {
        (open, Some(close))
    };
    let same = same_camera(&camera.0, &next.0)
        && match (&camera.1, &next.1) {
            (Some(a), Some(b)) => same_camera(a, b),
            (a, b) => a.is_none() && b.is_none(),
        };
    if !same {
        (camera.0, camera.1) = next;
    }
}

fn same_camera(a: &CameraDesc, b: &CameraDesc) -> bool {
    a == b
}

/// Sets keyframed emitted radiance for the frame (at mid-shutter).
pub fn animate_emission(time: Res<FrameTime>, keys: Res<EmitKeys>, mut materials: ResMut<Materials>) {
    if !time.is_changed() || keys.0.is_empty() {
        return;
    }
    let t = 0.5 * (time.open + time.close);
    let mut changed = false;
    for (id, track) in &keys.0 {
        // Curves that leave [0, MAX_EMISSION] are refused at load: this is rounding.
        let new = track.at(t).max(Vec3::ZERO);
        let m = &mut materials.bypass_change_detection().0[*id as usize];
        if m.emission().is_some_and(|e| e.emit != new) {
            m.set_emission(new);
            changed = true;
        }
    }
    if changed {
        materials.set_changed();
    }
}

/// Reads the frame's files of media whose grids are sequences. A medium's [`Filling`] is
/// written only when the files it is to read for the frame are not those it was read from, so
/// that a file named by frame after frame (or a frame rendered again) is not read again, nor
/// the volumes rebuilt. A frame whose files cannot be read reports why (the frame, the object,
/// the path looked for) and leaves the medium out until a frame's files are read.
#[expect(clippy::type_complexity, reason = "ECS queries name their components and filters in their types")]
pub fn read_grid_frames(
    frame: Res<FrameNumber>,
    mut media: Query<(Entity, &GridSequence, &mut GridInputs, Option<&mut Filling>, Option<&ObjectIndex>)>,
    mut reads: ResMut<GridReads>,
    mut errors: ResMut<FrameErrors>,
    mut commands: Commands,
) {
    let n = frame.0;
    for (e, sequence, mut held, filling, index) in &mut media {
        let paths: Vec<_> = sequence.0.sequences().map(|s| std::path::absolute(s.path(n))).collect();
        let holds = held.0.len() == paths.len()
            && held.0.iter().zip(&paths).all(|(f, p)| p.as_ref().is_ok_and(|p| *p == f.path));
        if holds && filling.is_some() {
            continue;
        }
        let _span = tracing::info_span!("read_grid_frames", frame = n).entered();
        match sequence.0.at_frame(n) {
            Ok((medium, files)) => {
                reads.0 += files.len() as u64;
                tracing::debug!(frame = n, files = ?files.iter().map(|f| &f.path).collect::<Vec<_>>(), "grid files read");
                held.0 = files;
                match filling {
                    // Files read again with the same values (after a reload) rebuild nothing.
                    Some(mut f) => {
                        f.set_if_neq(Filling(medium));
                    }
                    None => {
                        commands.entity(e).insert(Filling(medium));
                    }
                }
            }
            Err(why) => {
                let object = index.map_or_else(String::new, |i| format!("objects[{}]: ", i.0));
                errors.0.push(format!("frame {n}: {object}{why}"));
                held.0.clear();
                if filling.is_some() {
                    commands.entity(e).remove::<Filling>();
                }
            }
        }
    }
}
