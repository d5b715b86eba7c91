//! The shadow rays of one depth level, kept in the shading chunks that cast them.
//!
//! Shading runs in chunks of [`CHUNK`] rays and each chunk appends its shadow rays to a
//! buffer of its own. Those buffers are the queue: tracing runs over them chunk by
//! chunk, and since a chunk's shadow rays all belong to rays of that same chunk, each
//! task adds what arrived into its own slice of the rays' radiance. Nothing is copied
//! into one flat queue and no serial pass adds the results up.
//!
//! A buffer holds its rays in packets ([`ShadowPacket`]), side by side as the packet
//! query reads them: the lanes shading writes whole lanes (sample `k` of up to eight
//! hits, some lanes empty), the scalar loop fills a packet ray by ray. Queue order is
//! packet by packet, lane by lane; each owner's rays are in the order its hit cast them
//! (its samples in light order) either way, and each ray receives its shadow rays'
//! contributions in that order, so sums are bit for bit those of the scalar loop's queue.

use glam::Vec3;
use rayon::prelude::*;
use wide::u32x8;

use crate::accel::{PACKET, Ray, RayLanes};

/// Rays per rayon task and per shading chunk: large enough to amortise scheduling, small
/// enough to balance.
pub const CHUNK: usize = 1024;

/// A shadow ray: `contribution` reaches ray `owner`'s radiance if the path is clear.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowRay {
    /// From the shading point to the light sample; traced over `(0, 1 - SHADOW_EPSILON)`.
    pub ray: Ray,
    /// Unoccluded contribution, already weighted.
    pub contribution: Vec3,
    /// Index of the queued ray whose hit cast it.
    pub owner: u32,
}

/// Up to [`PACKET`] shadow rays side by side: lane `r` is a [`ShadowRay`] when bit `r`
/// of `rays.active` is set.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShadowPacket {
    /// The rays (`ShadowRay::ray`).
    pub rays: RayLanes,
    /// Each lane's `ShadowRay::contribution`, per colour channel.
    pub contribution: [[f32; PACKET]; 3],
    /// Each lane's `ShadowRay::owner`.
    pub owner: [u32; PACKET],
}

impl ShadowPacket {
    /// The shadow ray in lane `r`.
    pub fn get(&self, r: usize) -> ShadowRay {
        ShadowRay {
            ray: self.rays.ray(r),
            contribution: self.contribution(r),
            owner: self.owner[r],
        }
    }

    /// Lane `r`'s contribution.
    #[inline(always)]
    pub fn contribution(&self, r: usize) -> Vec3 {
        let c = &self.contribution;
        Vec3::new(c[0][r], c[1][r], c[2][r])
    }

    /// Puts `s` in lane `r` and marks the lane active.
    #[inline(always)]
    fn set(&mut self, r: usize, s: &ShadowRay) {
        self.rays.set(r, &s.ray);
        for a in 0..3 {
            self.contribution[a][r] = s.contribution[a];
        }
        self.owner[r] = s.owner;
    }
}

/// One shading chunk's shadow rays in queue order, in packets.
#[derive(Clone, Debug)]
pub struct ShadowPackets {
    /// The packets in use (the first `used`) and, past them, earlier depths' packets
    /// kept for reuse: a packet begun by [`Self::push`] is not zeroed first.
    packets: Vec<ShadowPacket>,
    /// Packets in use.
    used: usize,
    /// Rays in the packets in use.
    len: usize,
    /// Lanes [`Self::push`] has filled in the last packet; `PACKET` when it takes no
    /// more (full, or pushed whole by [`Self::push_packet_with`]) or there is none.
    open: usize,
}

impl Default for ShadowPackets {
    fn default() -> Self {
        Self {
            packets: Vec::new(),
            used: 0,
            len: 0,
            open: PACKET,
        }
    }
}

impl ShadowPackets {
    /// Appends `s` to the last packet if [`Self::push`] is filling it, else to a new
    /// packet: consecutive pushes make full packets.
    #[inline(always)]
    pub fn push(&mut self, s: ShadowRay) {
        if self.open >= PACKET {
            if self.used == self.packets.len() {
                self.packets.push(ShadowPacket::default());
            }
            // A reused packet's lanes are overwritten as they are filled.
            self.packets[self.used].rays.active = 0;
            self.used += 1;
            self.open = 0;
        }
        self.packets[self.used - 1].set(self.open, &s);
        self.open += 1;
        self.len += 1;
    }

    /// Appends a packet of its own that `fill` writes in place (a kept packet, not
    /// zeroed first: `fill` sets every field it needs, `rays.active` included), unless
    /// it leaves no lane holding a ray. In place: building it on the stack and copying
    /// it in cost 1.4% of the Cornell render.
    #[inline(always)]
    pub fn push_packet_with(&mut self, fill: impl FnOnce(&mut ShadowPacket)) {
        if self.used == self.packets.len() {
            self.packets.push(ShadowPacket::default());
        }
        let p = &mut self.packets[self.used];
        fill(p);
        let active = p.rays.active;
        if active != 0 {
            self.used += 1;
            self.len += active.count_ones() as usize;
            self.open = PACKET;
        }
    }

    /// The packets, in queue order.
    pub fn packets(&self) -> &[ShadowPacket] {
        &self.packets[..self.used]
    }

    /// Number of shadow rays.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are no shadow rays.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The shadow rays in queue order.
    pub fn iter(&self) -> impl Iterator<Item = ShadowRay> + '_ {
        self.packets()
            .iter()
            .flat_map(|p| p.rays.lanes().map(|r| p.get(r)))
    }

    /// Empties the buffer, keeping its packets for reuse.
    fn clear(&mut self) {
        self.used = 0;
        self.len = 0;
        self.open = PACKET;
    }
}

/// The shadow rays of one depth in queue order, held per shading chunk: chunk `c` holds
/// those cast by rays `c * CHUNK .. (c + 1) * CHUNK`, in order. The chunks' buffers are
/// kept between depths and regions: freeing them returned their pages to the kernel and
/// every region faulted them in anew (a tenth of the render's time in the kernel).
#[derive(Clone, Debug, Default)]
pub struct ShadowQueue {
    /// Each chunk's shadow rays; only the first `live` chunks belong to this depth.
    rays: Vec<ShadowPackets>,
    /// What each lane of each packet let through, chunk by chunk as `rays` (after
    /// tracing; one array per packet, stored whole rather than lane by lane).
    arrived: Vec<Vec<[Vec3; PACKET]>>,
    /// Chunks of the current depth.
    live: usize,
}

impl PartialEq for ShadowQueue {
    /// Equal when they hold the same shadow rays in the same order.
    fn eq(&self, other: &Self) -> bool {
        self.to_vec() == other.to_vec()
    }
}

impl ShadowQueue {
    /// A queue holding `rays`, whose owners must not decrease (queue order).
    pub fn from_rays(rays: &[ShadowRay]) -> Self {
        let mut queue = Self::default();
        let chunks = rays.last().map_or(0, |s| s.owner as usize / CHUNK + 1);
        let buffers = queue.start(chunks);
        for s in rays {
            buffers[s.owner as usize / CHUNK].push(*s);
        }
        queue
    }

    /// Empties the queue for a depth of `chunks` shading chunks and hands out their
    /// buffers (emptied, their allocations kept).
    pub fn start(&mut self, chunks: usize) -> &mut [ShadowPackets] {
        if self.rays.len() < chunks {
            self.rays.resize_with(chunks, ShadowPackets::default);
        }
        // Chunks past this depth's are emptied too, so no stale ray is ever read.
        self.rays.iter_mut().for_each(ShadowPackets::clear);
        self.arrived.iter_mut().for_each(Vec::clear);
        self.live = chunks;
        &mut self.rays[..chunks]
    }

    /// The current depth's shadow rays, chunk by chunk.
    pub fn chunks(&self) -> &[ShadowPackets] {
        &self.rays[..self.live]
    }

    /// Number of shadow rays.
    pub fn len(&self) -> usize {
        self.chunks().iter().map(ShadowPackets::len).sum()
    }

    /// Whether there are no shadow rays.
    pub fn is_empty(&self) -> bool {
        self.chunks().iter().all(ShadowPackets::is_empty)
    }

    /// The shadow rays in queue order.
    pub fn iter(&self) -> impl Iterator<Item = ShadowRay> + '_ {
        self.chunks().iter().flat_map(ShadowPackets::iter)
    }

    /// The shadow rays in queue order, copied into one vector.
    pub fn to_vec(&self) -> Vec<ShadowRay> {
        self.iter().collect()
    }

    /// Packets chunk `c`'s buffer holds for reuse (0 if it has none).
    pub fn chunk_capacity(&self, c: usize) -> usize {
        self.rays.get(c).map_or(0, |b| b.packets.len())
    }

    /// What each shadow ray let through, in queue order (empty before tracing).
    pub fn arrived(&self) -> Vec<Vec3> {
        let packets = self.chunks().iter().flat_map(ShadowPackets::packets);
        let arrived = self.arrived.iter().take(self.live).flatten();
        packets
            .zip(arrived)
            .flat_map(|(p, a)| p.rays.lanes().map(|r| a[r]))
            .collect()
    }

    /// Traces every shadow ray with `visible` (what of its contribution arrives) and adds
    /// the result to its owner's entry of `radiance`, one chunk per task.
    pub fn trace(&mut self, radiance: &mut [Vec3], visible: impl Fn(&ShadowRay) -> Vec3 + Sync) {
        self.trace_packets(radiance, true, |packet, arrived| {
            for r in packet.rays.lanes() {
                arrived[r] = visible(&packet.get(r));
            }
        });
    }

    /// [`Self::trace`] packet by packet: `visible(packet, arrived)` writes what of each
    /// active lane's contribution arrives into that lane of `arrived`; the results are
    /// added in queue order as there. Unless `keep_arrived`, what arrived is not kept
    /// ([`Self::arrived`] is then empty): only the debug recorder reads it, and a render
    /// storing it paid 1% of its time.
    pub fn trace_packets(
        &mut self,
        radiance: &mut [Vec3],
        keep_arrived: bool,
        visible: impl Fn(&ShadowPacket, &mut [Vec3; PACKET]) + Sync,
    ) {
        self.for_each_chunk(radiance, |radiance, first, rays, arrived| {
            for packet in rays.packets() {
                let mut lanes = [Vec3::ZERO; PACKET];
                visible(packet, &mut lanes);
                // Added packet by packet, lane by lane, in queue order: the same sums.
                for r in packet.rays.lanes() {
                    radiance[(packet.owner[r] - first) as usize] += lanes[r];
                }
                if keep_arrived {
                    arrived.push(lanes);
                }
            }
        });
    }

    /// Runs `chunk(radiance, first, rays, arrived)` on each live chunk in parallel: the
    /// chunk's part of `radiance` (whose first sample is `first`), its shadow rays, and
    /// its list of what arrived, empty.
    fn for_each_chunk(
        &mut self,
        radiance: &mut [Vec3],
        chunk: impl Fn(&mut [Vec3], u32, &ShadowPackets, &mut Vec<[Vec3; PACKET]>) + Sync,
    ) {
        let live = self.live;
        debug_assert!(
            live <= radiance.len().div_ceil(CHUNK),
            "rays without owners"
        );
        if self.arrived.len() < live {
            self.arrived.resize_with(live, Vec::new);
        }
        radiance
            .par_chunks_mut(CHUNK)
            .zip(self.rays[..live].par_iter())
            .zip(self.arrived[..live].par_iter_mut())
            .enumerate()
            .for_each(|(c, ((radiance, rays), arrived))| {
                // Appended packet by packet rather than zero-filled first and overwritten
                // (the fill was ~9 instructions per shadow ray); no entry of an earlier
                // depth can survive, as the chunk's vector is cleared and only extended.
                arrived.clear();
                chunk(radiance, (c * CHUNK) as u32, rays, arrived);
            });
    }
}

impl ShadowQueue {
    /// [`Self::trace_packets`] for binary visibility: `blocked(packet)` gives the lanes
    /// whose ray is occluded (bits of inactive lanes ignored); what arrives is each
    /// other active lane's contribution, 0 for a blocked one. The results are masked
    /// and added in lanes, with the same sums: a lane adds its contribution or +0 as
    /// there, and a lane without a ray adds -0, which leaves every value as it is.
    pub fn trace_blocked(
        &mut self,
        radiance: &mut [Vec3],
        keep_arrived: bool,
        blocked: impl Fn(&ShadowPacket) -> u32 + Sync,
    ) {
        self.for_each_chunk(radiance, |radiance, first, rays, arrived| {
            for packet in rays.packets() {
                let lanes = arrived_lanes(packet, blocked(packet));
                add_lanes(radiance, first, packet, &lanes);
                if keep_arrived {
                    arrived.push(std::array::from_fn(|r| {
                        let on = packet.rays.active & (1 << r) != 0;
                        let v = Vec3::new(lanes[0][r], lanes[1][r], lanes[2][r]);
                        if on { v } else { Vec3::ZERO }
                    }));
                }
            }
        });
    }
}

/// What of each lane's contribution arrives past the lanes `blocked`, per channel:
/// the contribution, +0 where blocked, and -0 in lanes without a ray (adding it
/// changes nothing, not even a -0).
#[inline(always)]
fn arrived_lanes(packet: &ShadowPacket, blocked: u32) -> [[f32; PACKET]; 3] {
    // Bit masks over whole vectors: a blocked lane's bits cleared (+0), an empty lane's
    // sign bit alone (-0). Selects lane by lane cost about 110 instructions a packet,
    // the compiler gathering each lane's three channels (Cornell direct: 357 -> 350
    // instructions per ray).
    let bit = u32x8::from([1, 2, 4, 8, 16, 32, 64, 128]);
    // All ones in the lanes of `mask`.
    let lanes = |mask: u32| (u32x8::splat(mask) & bit).simd_eq(bit);
    let active = packet.rays.active;
    let keep = lanes(active & !blocked);
    let empty = !lanes(active) & u32x8::splat(0x8000_0000);
    packet.contribution.map(|c| {
        let c = u32x8::from(c.map(f32::to_bits));
        ((c & keep) | empty).to_array().map(f32::from_bits)
    })
}

/// Adds lane `r` of `lanes` to `radiance[owner[r] - first]` for each active lane, in
/// lane order; when the owners are consecutive (the lanes shading's packets) every
/// lane is added, without a branch per lane (an inactive lane adds -0).
#[inline(always)]
fn add_lanes(radiance: &mut [Vec3], first: u32, packet: &ShadowPacket, lanes: &[[f32; PACKET]; 3]) {
    let o = packet.owner;
    let base = o[0].wrapping_sub(first) as usize;
    let mut step = true;
    for (r, &owner) in o.iter().enumerate() {
        step &= owner == o[0].wrapping_add(r as u32);
    }
    if step && base + PACKET <= radiance.len() {
        let window = &mut radiance[base..base + PACKET];
        for (r, x) in window.iter_mut().enumerate() {
            *x += Vec3::new(lanes[0][r], lanes[1][r], lanes[2][r]);
        }
        return;
    }
    for r in packet.rays.lanes() {
        radiance[(o[r] - first) as usize] += Vec3::new(lanes[0][r], lanes[1][r], lanes[2][r]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(super) fn shadow(owner: u32) -> ShadowRay {
        ShadowRay {
            ray: Ray {
                origin: Vec3::ZERO,
                dir: Vec3::X,
            },
            contribution: Vec3::splat(owner as f32 + 1.0),
            owner,
        }
    }

    #[test]
    fn rays_keep_queue_order_across_chunks() {
        let owners = [
            0,
            0,
            3,
            CHUNK as u32 - 1,
            CHUNK as u32,
            2 * CHUNK as u32 + 5,
        ];
        let rays: Vec<ShadowRay> = owners.iter().map(|&o| shadow(o)).collect();
        let queue = ShadowQueue::from_rays(&rays);
        assert_eq!(queue.len(), rays.len());
        assert_eq!(queue.to_vec(), rays);
        assert!(ShadowQueue::from_rays(&[]).is_empty());
    }

    #[test]
    fn tracing_adds_what_arrives_to_each_owner_in_order() {
        let owners = [
            0,
            0,
            5,
            CHUNK as u32 + 1,
            CHUNK as u32 + 1,
            2 * CHUNK as u32,
        ];
        let rays: Vec<ShadowRay> = owners.iter().map(|&o| shadow(o)).collect();
        let mut queue = ShadowQueue::from_rays(&rays);
        let mut radiance = vec![Vec3::ZERO; 2 * CHUNK + 1];
        // Rays of odd owners are blocked.
        queue.trace(&mut radiance, |s| {
            if s.owner % 2 == 1 {
                Vec3::ZERO
            } else {
                s.contribution
            }
        });
        let mut expected = vec![Vec3::ZERO; radiance.len()];
        for s in &rays {
            if s.owner % 2 == 0 {
                expected[s.owner as usize] += s.contribution;
            }
        }
        assert_eq!(radiance, expected);
        let arrived = queue.arrived();
        assert_eq!(arrived.len(), rays.len());
        assert_eq!(arrived[2], Vec3::ZERO, "owner 5 is blocked");
        assert_eq!(arrived[5], rays[5].contribution);
    }

    #[test]
    fn packets_are_consecutive_rays_of_one_chunk_added_in_order() {
        // 21 rays in chunk 0 (two full packets and a tail of 5), 3 in chunk 1.
        let owners: Vec<u32> = (0..21)
            .map(|i| i / 4)
            .chain([CHUNK as u32, CHUNK as u32 + 2, CHUNK as u32 + 2])
            .collect();
        let rays: Vec<ShadowRay> = owners.iter().map(|&o| shadow(o)).collect();
        let mut by_ray = ShadowQueue::from_rays(&rays);
        let mut by_packet = ShadowQueue::from_rays(&rays);
        let mut radiance = vec![Vec3::ZERO; CHUNK + 3];
        let mut expected = radiance.clone();
        // Rays of odd owners are blocked.
        let visible = |s: &ShadowRay| s.contribution * s.owner.is_multiple_of(2) as u32 as f32;
        by_ray.trace(&mut expected, visible);
        let packets = std::sync::Mutex::new(Vec::new());
        by_packet.trace_packets(&mut radiance, true, |packet, arrived| {
            let owners = packet.rays.lanes().map(|r| packet.owner[r]);
            packets.lock().unwrap().push(owners.collect::<Vec<_>>());
            for r in packet.rays.lanes() {
                arrived[r] = visible(&packet.get(r));
            }
        });
        assert_eq!(radiance, expected);
        assert_ne!(expected, vec![Vec3::ZERO; CHUNK + 3]);
        assert_eq!(by_packet.arrived(), by_ray.arrived());
        let mut packets = packets.into_inner().unwrap();
        packets.sort();
        let sizes: Vec<usize> = packets.iter().map(Vec::len).collect();
        assert_eq!(sizes, [8, 8, 5, 3]);
        assert_eq!(packets.concat(), owners, "consecutive, in queue order");
    }

    #[test]
    fn a_second_trace_leaves_no_stale_arrival() {
        // 11 rays in chunk 0 (a packet and a tail of 3), 2 in chunk 1.
        let owners: Vec<u32> = (0..11).chain([CHUNK as u32, CHUNK as u32 + 1]).collect();
        let rays: Vec<ShadowRay> = owners.iter().map(|&o| shadow(o)).collect();
        let mut queue = ShadowQueue::from_rays(&rays);
        let mut radiance = vec![Vec3::ZERO; CHUNK + 2];
        queue.trace(&mut radiance, |s| s.contribution);
        // The next depth: the same chunks with fewer rays, all blocked.
        let buffers = queue.start(2);
        rays[..5].iter().for_each(|s| buffers[0].push(*s));
        buffers[1].push(rays[11]);
        let mut radiance = vec![Vec3::ZERO; CHUNK + 2];
        queue.trace(&mut radiance, |_| Vec3::ZERO);
        assert_eq!(queue.arrived(), vec![Vec3::ZERO; 6]);
        assert_eq!(radiance, vec![Vec3::ZERO; CHUNK + 2]);
    }

    #[test]
    fn packets_pushed_whole_keep_their_lanes_and_empty_ones_are_dropped() {
        fn whole(lanes: &[usize]) -> impl FnOnce(&mut ShadowPacket) + '_ {
            move |p| {
                p.rays.active = 0;
                for &r in lanes {
                    p.set(r, &shadow(r as u32));
                }
            }
        }
        let mut queue = ShadowQueue::default();
        for _ in 0..2 {
            // The second round reuses the first one's packets: no stale lane comes back.
            let buffers = queue.start(1);
            buffers[0].push(shadow(0));
            buffers[0].push_packet_with(whole(&[1, 3]));
            buffers[0].push_packet_with(whole(&[]));
            buffers[0].push(shadow(4));
            buffers[0].push(shadow(5));
            assert_eq!(buffers[0].packets().len(), 3, "a push after a whole packet");
            let owners: Vec<u32> = queue.iter().map(|s| s.owner).collect();
            assert_eq!(owners, [0, 1, 3, 4, 5]);
            assert_eq!(queue.len(), 5);
            assert_eq!(queue.to_vec()[2], shadow(3));
        }
        let buffers = queue.start(1);
        buffers[0].push_packet_with(whole(&[6]));
        assert_eq!(queue.to_vec(), [shadow(6)]);
    }

    #[test]
    fn start_empties_every_chunk_and_keeps_buffers() {
        let rays: Vec<ShadowRay> = [0, CHUNK as u32, 2 * CHUNK as u32]
            .iter()
            .map(|&o| shadow(o))
            .collect();
        let mut queue = ShadowQueue::from_rays(&rays);
        let chunks = queue.start(1);
        assert_eq!(chunks.len(), 1);
        assert!(chunks[0].is_empty());
        assert!(queue.is_empty());
        assert!(
            queue.chunk_capacity(2) >= 1,
            "a later chunk keeps its buffer"
        );
        queue.start(3);
        assert!(queue.is_empty(), "no stale ray comes back");
    }
}

#[cfg(test)]
mod blocked_tests {
    use super::*;

    /// A packet of its own with owners `at..at + 8`, lanes `active` holding rays.
    fn whole(buffer: &mut ShadowPackets, at: u32, active: u32) {
        buffer.push_packet_with(|p| {
            for r in 0..PACKET {
                p.owner[r] = at + r as u32;
                for (a, scale) in [1.0, -0.5, 0.25].into_iter().enumerate() {
                    // Lane 0 of a packet at 0 gives -0 in the second channel.
                    p.contribution[a][r] = (at + r as u32) as f32 * scale;
                }
            }
            p.rays = RayLanes::default();
            p.rays.active = active;
        });
    }

    #[test]
    fn blocked_lanes_add_bit_for_bit_what_the_packet_loop_adds() {
        let mut queue = ShadowQueue::default();
        let buffers = queue.start(2);
        let base = CHUNK as u32;
        whole(&mut buffers[0], 0, 0xff);
        whole(&mut buffers[0], 8, 0b1011_0110);
        for owner in [16, 16, 17] {
            let mut s = super::tests::shadow(owner);
            s.contribution.y = -0.0;
            buffers[0].push(s);
        }
        whole(&mut buffers[0], 20, 0);
        whole(&mut buffers[0], base - 8, 0xff);
        // The short last chunk (13 rays): a packet that ends at its end, one past it.
        whole(&mut buffers[1], base + 5, 0xff);
        whole(&mut buffers[1], base + 8, 0b1_1111);
        // Starting values that an addition of +0 would change (-0), NaN, others.
        let start: Vec<Vec3> = (0..CHUNK + 13)
            .map(|i| match i % 4 {
                0 => Vec3::splat(-0.0),
                1 => Vec3::new(0.0, -0.0, 1.5),
                2 => Vec3::new(f32::NAN, 2.0, -3.0),
                _ => Vec3::splat(i as f32 * 0.25),
            })
            .collect();
        let blocked = |p: &ShadowPacket| {
            (0..PACKET).fold(0, |m, r| m | (p.owner[r].is_multiple_of(3) as u32) << r)
        };
        let mut by_lane = queue.clone();
        let mut want = start.clone();
        by_lane.trace_packets(&mut want, true, |p, arrived| {
            let b = blocked(p);
            for r in p.rays.lanes() {
                arrived[r] = if b & (1 << r) != 0 {
                    Vec3::ZERO
                } else {
                    p.contribution(r)
                };
            }
        });
        let mut got = start.clone();
        queue.trace_blocked(&mut got, true, blocked);
        let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
            v.iter().map(|x| x.to_array().map(f32::to_bits)).collect()
        };
        assert_eq!(bits(&got), bits(&want));
        assert_ne!(bits(&got), bits(&start));
        assert_eq!(bits(&queue.arrived()), bits(&by_lane.arrived()));
        // Without keeping what arrived, the same sums and nothing kept.
        let mut again = start.clone();
        queue.trace_blocked(&mut again, false, blocked);
        assert_eq!(bits(&again), bits(&want));
        assert!(queue.arrived().is_empty());
    }
}
