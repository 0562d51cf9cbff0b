//! Tracking moving obstacles across LiDAR scans: a velocity for each
//! inferred piece, for the controller's moving-obstacle barrier.
//!
//! The method, per scan (time `t`, s; the pieces of [`crate::sense::infer_obstacles`]):
//!
//! 1. **Measurement**: each piece's centre of vertices `z` (m, world frame W).
//! 2. **Prediction**: every track's constant-velocity Kalman filter (state
//!    `[x, y, vx, vy]`, white-noise acceleration of spectral density
//!    [`TrackParams::accel_noise`] m^2/s^3, the discrete model of Bar-Shalom,
//!    Li and Kirubarajan, "Estimation with Applications to Tracking and
//!    Navigation", 2001, section 6.2.2) is predicted to `t`.
//! 3. **Data association**: global nearest neighbour (`sense/assign.rs`):
//!    a (track, piece) pair is inside the gate when the piece's centre is
//!    within [`TrackParams::gate`] m of the track's prediction and within
//!    the squared Mahalanobis distance [`TrackParams::gate_chi2`] in the
//!    innovation covariance (a settled track gates tightly, a new or coasting
//!    one widely); the pairs are chosen by the Hungarian method to minimise
//!    the summed squared Mahalanobis distance, a track left unmatched
//!    costing the gate (Blackman and Popoli, 1999, section 6.4; the ROS leg
//!    tracker of Leigh et al. associates so). Greedy nearest-first pairing
//!    lets one track take the piece its neighbour needs when two people walk
//!    close together; the global optimum does not.
//! 4. **Update**: a matched track's filter is updated with `z` (measurement
//!    noise [`TrackParams::measurement_sigma`] m per axis); an unmatched piece
//!    starts a track at rest with a wide velocity prior; a track not matched
//!    for [`TrackParams::max_age`] s is dropped, a moving one (below) after
//!    [`TrackParams::max_coast`] s (it coasts at its estimated velocity: a
//!    person hidden behind another for a moment).
//! 5. **Velocity out**: a piece gets its track's velocity when the track is
//!    confirmed (at least [`TrackParams::confirm`] updates), the piece is
//!    person-sized (every vertex within [`TrackParams::max_extent`] m of its
//!    centre: a wall seen in pieces whose centres slide along it as the robot
//!    walks is not a person) and the estimated speed is at least
//!    [`TrackParams::min_speed`] and either [`TrackParams::significance`]
//!    standard deviations of the filter's velocity estimate or the track has
//!    just travelled [`TrackParams::still_radius`] (in the filter's steady
//!    state two standard deviations are about 0.31 m/s, so a person walking
//!    slower was never significant: `crowd` seed 614, a person at 0.3 m/s
//!    left at rest, in the map, for 2.8 s while the robot walked into them);
//!    otherwise zero (at rest).
//!    Moving is sticky: a track that got a velocity once keeps giving its
//!    current estimate, whatever the size of the piece it is matched with,
//!    until it has stayed within [`TrackParams::still_radius`] of one point
//!    for [`TrackParams::still_time`] (a person standing, or a wall's end
//!    whose visible part slid as the robot walked past): it is then at rest
//!    until it leaves that disk; and a track matched with a flat face
//!    ([`flat`]: never a person) is at rest.
//! 6. **Velocity uncertainty** ([`Track::velocity_radius`]): with each
//!    velocity a radius (m/s) the true velocity is within, in any
//!    direction, while the model holds: the [`TrackParams::velocity_chi2`]
//!    confidence disk of the filter's velocity block (its largest
//!    eigenvalue), at most the speed plus [`TrackParams::walking_speed`];
//!    [`TrackParams::walking_speed`] for a piece not known to move (a new,
//!    unconfirmed or just re-found track, handed over at rest). A coasting
//!    track's covariance grows with every prediction, and so does its
//!    radius.
//!
//! The tracker only sees the pieces it is given; it keeps no map. In the
//! closed loop the pieces are the convex hulls of each scan's DBSCAN clusters,
//! and [`crate::sense::movers`] keeps the hits of those that may move out of
//! the occupancy map.

use ldcbf_controller::nalgebra::{Matrix2, Matrix4, Vector2, Vector4};

use super::assign::assign;
use crate::world::Polygon;
use crate::world::moving::{MAX_SPEED, vertex_centre as centre};

/// Tracker settings. Lengths in m, times in s.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackParams {
    /// DBSCAN radius of the clusters [`crate::sense::movers`] tracks, m (at
    /// most the LiDAR's `eps`): smaller than the map's so that two people a
    /// few decimetres apart, or a person passing a wall, stay two clusters.
    pub cluster_eps: f64,
    /// Largest distance between a track's predicted position and a piece's
    /// centre for the two to be associated, m.
    pub gate: f64,
    /// Largest squared Mahalanobis distance of a piece's centre from a
    /// track's prediction (in the innovation covariance) for the two to be
    /// associated (chi-square, 2 degrees of freedom; 13.8 keeps 99.9 % of
    /// the right pairs); also the cost of leaving a track unmatched.
    pub gate_chi2: f64,
    /// White-noise acceleration spectral density of the constant-velocity
    /// model, m^2/s^3.
    pub accel_noise: f64,
    /// Standard deviation of a piece centre, m per axis.
    pub measurement_sigma: f64,
    /// Standard deviation of a new track's velocity, m/s per axis.
    pub initial_speed_sigma: f64,
    /// A track unmatched this long is dropped, s.
    pub max_age: f64,
    /// A moving track unmatched this long is dropped, s (at least `max_age`).
    pub max_coast: f64,
    /// Updates before a track's velocity is used.
    pub confirm: u32,
    /// Largest distance of a piece's vertex from its centre for the piece to
    /// get a velocity, m.
    pub max_extent: f64,
    /// Speeds below this are reported as at rest, m/s.
    pub min_speed: f64,
    /// Speeds below this many standard deviations of the velocity estimate
    /// are reported as at rest (the centre of a piece at rest jitters with
    /// the noise and the view).
    pub significance: f64,
    /// The speed a person may walk at, m/s: the velocity uncertainty radius
    /// of a piece whose motion is not known ([`Track::velocity_radius`]).
    pub walking_speed: f64,
    /// Chi-square quantile (2 degrees of freedom) of the velocity
    /// uncertainty radius ([`Track::velocity_radius`]; 9.21: 99 %).
    pub velocity_chi2: f64,
    /// Largest distance of a cluster's vertex from its centre for the
    /// cluster to be one person, m: a wider cluster is split
    /// ([`crate::sense::movers`]); a person's radius is 0.2-0.3 m.
    pub person_extent: f64,
    /// Two consecutive hits of a cluster (in ray order) farther apart than
    /// this, or with a ray between them that hit something else or nothing,
    /// are a break between two things ([`crate::sense::movers`]), m.
    pub segment_jump: f64,
    /// Largest distance of a piece's vertex from its centre for the piece
    /// to be cut into person-wide pieces by size ([`crate::sense::movers`]:
    /// two or three people side by side), m.
    pub group_extent: f64,
    /// A piece whose hits' RMS distance from their principal line is at
    /// most this is straight (a wall's face), and is not cut by size, m.
    pub line_rms: f64,
    /// A piece at most this thick across and longer than 0.4 m is a flat
    /// face ([`flat`]): never a person, m (a wall's hull is the LiDAR's
    /// `min_thickness`, 0.05 m, plus its noise).
    pub flat_width: f64,
    /// Hits on a straight face at least this long are a wall's, never a
    /// person's, and are left to the map ([`crate::sense::walls`]), m: a
    /// person's outline is round; the simulator's people are octagons of
    /// radius at most 0.3 m, all turned alike, whose faces are at most 0.23
    /// m long, and two of them side by side can line their faces up across
    /// a gap the breakpoint detector links (about 0.25 m at 2 m): at 0.5 m
    /// such pairs in a crowd were taken for walls (`crowd` seed 601: a
    /// robot-caused contact), at 0.8 m none was.
    pub wall_length: f64,
    /// A track whose estimated position has stayed within this distance of
    /// one point for [`TrackParams::still_time`] is at rest, m (see there).
    pub still_radius: f64,
    /// A track that has stayed within [`TrackParams::still_radius`] of one
    /// point this long is at rest, and is given no velocity until it leaves
    /// that disk, s: moving is sticky, and without this a thing that looked
    /// like it moved once stayed a person for good. The visible part of a
    /// wall's end (a door jamb) slides by up to its length as the robot
    /// walks past, which looked like a significant speed (`door-emerge`
    /// seed 700: a jamb given 0.05 m/s, whose reachable set with that of a
    /// person standing beyond the door held the robot for 60 s); a person
    /// who stands still this long is at rest too, until they walk on. A
    /// track younger than this is not judged by it (a person who appears
    /// gets a velocity as soon as it is significant).
    pub still_time: f64,
}

impl Default for TrackParams {
    fn default() -> Self {
        TrackParams {
            cluster_eps: 0.15,
            gate: 0.5,
            gate_chi2: 13.8,
            accel_noise: 0.1,
            measurement_sigma: 0.05,
            initial_speed_sigma: 1.0,
            max_age: 0.3,
            max_coast: 1.0,
            confirm: 10,
            max_extent: 0.5,
            min_speed: 0.15,
            significance: 2.0,
            walking_speed: 1.5,
            velocity_chi2: 9.21,
            person_extent: 0.35,
            segment_jump: 0.12,
            group_extent: 1.0,
            line_rms: 0.04,
            flat_width: 0.065,
            wall_length: 0.8,
            still_radius: 0.3,
            still_time: 2.0,
        }
    }
}

/// One track: a constant-velocity Kalman filter.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    /// Identifier, unique within a tracker (in order of creation).
    pub id: u64,
    /// State `[x, y, vx, vy]` (m, m/s) at `time`.
    pub state: Vector4<f64>,
    /// State covariance.
    pub covariance: Matrix4<f64>,
    /// Time of the state, s.
    pub time: f64,
    /// Time of the last update, s.
    pub last_update: f64,
    /// Updates received (the first measurement included).
    pub updates: u32,
    /// The point the estimated position has stayed within
    /// [`TrackParams::still_radius`] of since `anchor_time` (s), m.
    pub anchor: Vector2<f64>,
    /// Since when the position has stayed near `anchor` (the track's start
    /// at the latest), s.
    pub anchor_time: f64,
    /// The track has been given a velocity ([`Motion::Moving`]): from then
    /// on it is moving, with its current estimate (a person who slows, or
    /// whose visible outline shifts its centre against the walk, is not
    /// turned into a wall), until it stays still for
    /// [`TrackParams::still_time`] or is matched with a flat face.
    pub moving: bool,
    /// The last piece matched with the track was person-sized
    /// ([`TrackParams::max_extent`]): the track may be a person, and a
    /// cluster it predicts into is split at it ([`crate::sense::movers`]).
    pub small: bool,
}

impl Track {
    /// Estimated position, m.
    pub fn position(&self) -> Vector2<f64> {
        Vector2::new(self.state[0], self.state[1])
    }
    /// Estimated velocity, m/s.
    pub fn velocity(&self) -> Vector2<f64> {
        Vector2::new(self.state[2], self.state[3])
    }

    fn predict(&mut self, t: f64, q: f64) {
        let dt = t - self.time;
        if dt <= 0.0 {
            return;
        }
        let mut f = Matrix4::identity();
        f[(0, 2)] = dt;
        f[(1, 3)] = dt;
        let (d2, d3) = (dt * dt / 2.0, dt * dt * dt / 3.0);
        let mut qm = Matrix4::zeros();
        for a in 0..2 {
            qm[(a, a)] = d3 * q;
            qm[(a, a + 2)] = d2 * q;
            qm[(a + 2, a)] = d2 * q;
            qm[(a + 2, a + 2)] = dt * q;
        }
        self.state = f * self.state;
        self.covariance = f * self.covariance * f.transpose() + qm;
        self.time = t;
    }

    /// The innovation covariance of a centre measured with `sigma` (m per
    /// axis): the position block of the covariance plus `R = sigma^2 I`
    /// (`H = [I 0]`), m^2.
    pub fn innovation_covariance(&self, sigma: f64) -> Matrix2<f64> {
        self.covariance.fixed_view::<2, 2>(0, 0) + Matrix2::identity() * (sigma * sigma)
    }

    /// The velocity uncertainty radius, m/s: the true velocity is within it
    /// of [`Track::velocity`] while the filter's model holds. The radius of
    /// the `p.velocity_chi2` confidence disk of the velocity block `P_v` of
    /// the covariance (its largest eigenvalue, a circle around the ellipse:
    /// `sqrt(chi2 * lambda_max(P_v))`), at most the speed plus
    /// [`TrackParams::walking_speed`] (a person walks no faster); a track not
    /// confirmed yet ([`TrackParams::confirm`]) or not moving gets
    /// [`TrackParams::walking_speed`] (handed over at rest, it may walk off
    /// in any direction).
    pub fn velocity_radius(&self, p: &TrackParams) -> f64 {
        if !self.moving {
            return p.walking_speed;
        }
        let pv = self.covariance.fixed_view::<2, 2>(2, 2);
        let (a, b, c) = (pv[(0, 0)], 0.5 * (pv[(0, 1)] + pv[(1, 0)]), pv[(1, 1)]);
        let lambda = 0.5 * (a + c) + (0.25 * (a - c) * (a - c) + b * b).sqrt();
        let r = (p.velocity_chi2 * lambda.max(0.0)).sqrt();
        if r.is_finite() {
            r.min(self.velocity().norm() + p.walking_speed)
        } else {
            p.walking_speed
        }
    }

    fn update(&mut self, z: Vector2<f64>, sigma: f64) {
        let p = self.covariance;
        let s = self.innovation_covariance(sigma);
        let Some(s_inv) = s.try_inverse() else {
            return;
        };
        let k = p.fixed_view::<4, 2>(0, 0) * s_inv;
        let y = z - self.position();
        self.state += k * y;
        let mut i_kh = Matrix4::identity();
        i_kh.fixed_view_mut::<4, 2>(0, 0).copy_from(&(-k));
        for a in 0..2 {
            i_kh[(a, a)] += 1.0;
        }
        self.covariance = i_kh * p;
        self.covariance = 0.5 * (self.covariance + self.covariance.transpose());
        self.last_update = self.time;
        self.updates += 1;
    }
}

/// Tracks across scans (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct Tracker {
    params: TrackParams,
    tracks: Vec<Track>,
    next_id: u64,
    /// The id of the track each piece of the last scan was matched with.
    matched: Vec<u64>,
}

impl Tracker {
    /// A tracker with no track yet.
    pub fn new(params: TrackParams) -> Self {
        Tracker {
            params,
            tracks: Vec::new(),
            next_id: 0,
            matched: Vec::new(),
        }
    }

    /// The settings.
    pub fn params(&self) -> &TrackParams {
        &self.params
    }

    /// The id of the track each piece of the last scan was matched with (or
    /// started), in the pieces' order.
    pub fn matched(&self) -> &[u64] {
        &self.matched
    }

    /// The current tracks.
    pub fn tracks(&self) -> &[Track] {
        &self.tracks
    }

    /// The velocity uncertainty radius of track `id`, m/s
    /// ([`Track::velocity_radius`]); [`TrackParams::walking_speed`] for a
    /// track that does not live.
    pub fn velocity_radius(&self, id: u64) -> f64 {
        self.tracks
            .iter()
            .find(|tr| tr.id == id)
            .map_or(self.params.walking_speed, |tr| {
                tr.velocity_radius(&self.params)
            })
    }

    /// The tracks that may be people ([`Track::small`], or moving) at time
    /// `t` (s): each one's id, its position (m; moving tracks predicted at
    /// their estimated velocities, the others where they were last seen) and
    /// whether it moves ([`Track::moving`]).
    pub fn people_at(&self, t: f64) -> Vec<(u64, Vector2<f64>, bool)> {
        self.tracks
            .iter()
            .filter(|tr| tr.small || tr.moving)
            .map(|tr| {
                let dt = if tr.moving {
                    (t - tr.time).max(0.0)
                } else {
                    0.0
                };
                (tr.id, tr.position() + tr.velocity() * dt, tr.moving)
            })
            .collect()
    }

    /// One scan at time `t` (s, non-decreasing) with its pieces: updates the
    /// tracks and returns one velocity per piece (m/s, world frame; zero for a
    /// piece taken as at rest).
    pub fn update(&mut self, t: f64, pieces: &[Polygon]) -> Vec<Vector2<f64>> {
        self.classify(t, pieces)
            .into_iter()
            .map(|m| match m {
                Motion::Moving(v) => v,
                Motion::Tentative | Motion::AtRest => Vector2::zeros(),
            })
            .collect()
    }

    /// The association of the predicted tracks with the piece centres `z`
    /// (m): per track, its piece or `None` (module docs, step 3).
    fn associate(&self, z: &[Vector2<f64>]) -> Vec<Option<usize>> {
        let pr = &self.params;
        let cost: Vec<Vec<Option<f64>>> = self
            .tracks
            .iter()
            .map(|tr| {
                let s_inv = tr.innovation_covariance(pr.measurement_sigma).try_inverse();
                z.iter()
                    .map(|zj| {
                        let y = zj - tr.position();
                        let d2 = s_inv.map(|si| (y.transpose() * si * y)[(0, 0)])?;
                        (y.norm() <= pr.gate && d2 <= pr.gate_chi2).then_some(d2)
                    })
                    .collect()
            })
            .collect();
        assign(&cost, pr.gate_chi2)
    }

    /// As [`Tracker::update`], with what the tracker knows of each piece:
    /// [`Motion::Moving`] with the velocity [`Tracker::update`] gives,
    /// [`Motion::AtRest`] for a confirmed track (or a piece too large to be a
    /// person) without a significant speed, [`Motion::Tentative`] for a
    /// person-sized piece whose track is not confirmed yet.
    pub fn classify(&mut self, t: f64, pieces: &[Polygon]) -> Vec<Motion> {
        let pr = self.params.clone();
        for tr in &mut self.tracks {
            tr.predict(t, pr.accel_noise);
        }
        let z: Vec<Vector2<f64>> = pieces.iter().map(centre).collect();
        let mut track_of: Vec<Option<usize>> = vec![None; pieces.len()];
        for (i, j) in self.associate(&z).into_iter().enumerate() {
            if let Some(j) = j {
                track_of[j] = Some(i);
                self.tracks[i].update(z[j], pr.measurement_sigma);
            }
        }
        for (j, slot) in track_of.iter_mut().enumerate() {
            if slot.is_none() {
                let mut cov = Matrix4::zeros();
                let (ps, vs) = (pr.measurement_sigma, pr.initial_speed_sigma);
                cov[(0, 0)] = ps * ps;
                cov[(1, 1)] = ps * ps;
                cov[(2, 2)] = vs * vs;
                cov[(3, 3)] = vs * vs;
                self.tracks.push(Track {
                    id: self.next_id,
                    state: Vector4::new(z[j].x, z[j].y, 0.0, 0.0),
                    covariance: cov,
                    time: t,
                    last_update: t,
                    updates: 1,
                    anchor: z[j],
                    anchor_time: t,
                    moving: false,
                    small: false,
                });
                self.next_id += 1;
                *slot = Some(self.tracks.len() - 1);
            }
        }
        let self_ids: Vec<u64> = self.tracks.iter().map(|tr| tr.id).collect();
        let out = pieces
            .iter()
            .zip(&track_of)
            .map(|(p, slot)| {
                let tr = &mut self.tracks[slot.expect("every piece has a track")];
                let is_flat = flat(p, pr.flat_width);
                let small = person_sized(p, pr.max_extent) && !is_flat;
                tr.small = small;
                // Bounded as the scenario's obstacles are (a wrong
                // association must not hand the controller an absurd speed).
                let v = tr.velocity();
                let v = v * (MAX_SPEED / v.norm()).min(1.0);
                let sigma_v = (0.5 * (tr.covariance[(2, 2)] + tr.covariance[(3, 3)])).sqrt();
                // Left the disk it stayed in: it travelled still_radius.
                let travelled = (tr.position() - tr.anchor).norm() > pr.still_radius;
                if travelled {
                    tr.anchor = tr.position();
                    tr.anchor_time = t;
                }
                // Near one point for still_time (so at least that old): at rest.
                let still = t - tr.anchor_time >= pr.still_time;
                // A flat face is never a person ([`flat`]): a track that
                // moved (the visible part of a wall's end sliding as the
                // robot walks past) and is now matched with one is at rest.
                if still || is_flat {
                    tr.moving = false;
                }
                if tr.moving {
                    // Sticky (module docs), also when the piece grew (people
                    // seen as one cluster that the split did not part).
                    Motion::Moving(v)
                } else if !small {
                    Motion::AtRest
                } else if tr.updates < pr.confirm {
                    Motion::Tentative
                } else if !still
                    && v.norm() >= pr.min_speed
                    && (v.norm() >= pr.significance * sigma_v || travelled)
                {
                    tr.moving = true;
                    Motion::Moving(v)
                } else {
                    Motion::AtRest
                }
            })
            .collect();
        self.tracks.retain(|tr| {
            t - tr.last_update
                <= if tr.moving {
                    pr.max_coast.max(pr.max_age)
                } else {
                    pr.max_age
                }
        });
        self.matched = track_of
            .iter()
            .map(|slot| self_ids[slot.expect("every piece has a track")])
            .collect();
        out
    }
}

/// Whether `p` could be one person: every vertex within `max_extent` (m) of
/// its vertex centre.
pub fn person_sized(p: &Polygon, max_extent: f64) -> bool {
    let c = centre(p);
    p.vertices().iter().all(|v| (v - c).norm() <= max_extent)
}

/// Whether `p` is a flat face, not a person: longer than most of a
/// person's outline (some vertex farther than 0.2 m from its centre) and at
/// most `width` (m) across (its smallest extent over its edges' normals;
/// the outline of a person of radius 0.2-0.3 m seen over a chord of 0.4 m
/// bulges at least 0.076 m). A
/// person's outline is round: the piece of a wall cut off by the shadow of
/// a person walking in front of it slides along the wall with the shadow,
/// and is not a person.
pub fn flat(p: &Polygon, width: f64) -> bool {
    let v = p.vertices();
    let c = centre(p);
    if v.iter().all(|q| (q - c).norm() <= 0.2) {
        return false;
    }
    let thinnest = (0..v.len())
        .map(|k| {
            let e = v[(k + 1) % v.len()] - v[k];
            let n = Vector2::new(-e.y, e.x) / e.norm().max(f64::MIN_POSITIVE);
            v.iter()
                .map(|q| (q - v[k]).dot(&n).abs())
                .fold(0.0, f64::max)
        })
        .fold(f64::MAX, f64::min);
    thinnest <= width
}

/// What the tracker knows of a piece ([`Tracker::classify`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    /// Person-sized, its track not confirmed yet: may move.
    Tentative,
    /// At rest (confirmed without a significant speed, or not person-sized).
    AtRest,
    /// Moving at this velocity, m/s, world frame.
    Moving(Vector2<f64>),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sense::{Lidar, LidarParams};
    use crate::world::moving::translated;
    use crate::world::random::regular_polygon;

    /// A recorded crossing: a LiDAR at rest at the origin scans at 20 Hz a
    /// person (octagon, radius 0.25 m) crossing 2 m ahead at 0.5 m/s, a pillar
    /// and a wall at rest. Returns, per scan, the time, the pieces, the
    /// velocities the tracker gave them, and the person's true centre.
    #[allow(clippy::type_complexity)]
    fn recorded_crossing() -> Vec<(f64, Vec<Polygon>, Vec<Vector2<f64>>, Vector2<f64>)> {
        let person = Polygon::new(&regular_polygon([2.0, -2.0], 0.25, 8, 0.1)).unwrap();
        let pillar = Polygon::new(&regular_polygon([-1.5, 1.0], 0.2, 6, 0.0)).unwrap();
        let wall = Polygon::new(&[[-2.0, -2.0], [0.5, -2.0], [0.5, -1.8], [-2.0, -1.8]]).unwrap();
        let v = Vector2::new(0.0, 0.5);
        let mut lidar = Lidar::new(LidarParams::default(), 7).unwrap();
        let mut tracker = Tracker::new(TrackParams::default());
        (0..160)
            .map(|k| {
                let t = 0.05 * k as f64;
                let p = translated(&person, v * t);
                let map = [p, pillar, wall];
                let (_, pieces) = lidar.perceive(Vector2::zeros(), 0.0, &map);
                let vel = tracker.update(t, &pieces);
                (t, pieces, vel, centre(&p))
            })
            .collect()
    }

    #[test]
    fn tracks_a_person_crossing_and_leaves_walls_at_rest() {
        let rec = recorded_crossing();
        let truth_v = Vector2::new(0.0, 0.5);
        let (mut person, mut tracked, mut close) = (0, 0, 0);
        for (t, pieces, vel, truth) in &rec {
            assert_eq!(pieces.len(), vel.len());
            for (p, v) in pieces.iter().zip(vel) {
                let c = centre(p);
                if (c - truth).norm() < 0.4 {
                    // The person, after the filter has settled (1 s): within
                    // 0.35 m/s of the truth (most within 0.15; a track that
                    // took over when the person was seen as two pieces keeps
                    // its estimate while it settles), or at rest while such a
                    // track confirms.
                    if *t >= 1.0 {
                        person += 1;
                        if *v != Vector2::zeros() {
                            let e = (v - truth_v).norm();
                            assert!(e < 0.35, "t = {t}: person piece at {c} got {v}");
                            tracked += 1;
                            close += usize::from(e < 0.15);
                        }
                    }
                } else {
                    assert_eq!(*v, Vector2::zeros(), "t = {t}: piece at {c} is at rest");
                }
            }
        }
        assert!(person > 100, "the person was seen in most scans ({person})");
        assert!(
            tracked as f64 >= 0.8 * person as f64,
            "the person had a velocity in {tracked} of {person} pieces"
        );
        assert!(
            close as f64 >= 0.9 * tracked as f64,
            "within 0.15 m/s in {close} of {tracked}"
        );
    }

    #[test]
    fn a_new_track_is_at_rest_until_confirmed() {
        let mut tr = Tracker::new(TrackParams::default());
        let sq = |x: f64| Polygon::new(&regular_polygon([x, 0.0], 0.2, 8, 0.0)).unwrap();
        // A piece moving at 1 m/s along x, seen at 20 Hz.
        for k in 0..9 {
            let v = tr.update(0.05 * k as f64, &[sq(0.05 * k as f64)]);
            assert_eq!(v, vec![Vector2::zeros()], "scan {k}: not confirmed yet");
        }
        let v = tr.update(0.45, &[sq(0.45)]);
        assert!(v[0].x > 0.5, "confirmed at the 10th update: {}", v[0]);
        assert_eq!(tr.tracks().len(), 1, "one track followed the piece");
        // Gone for longer than max_coast (a moving track): dropped; a far
        // piece starts a new one.
        tr.update(1.5, &[sq(3.0)]);
        assert_eq!(tr.tracks().len(), 1);
        assert_eq!(tr.tracks()[0].id, 1);
    }
}
