//! The kept, patched mesh frame (`mesh_patch.rs`) against the whole-frame
//! encoder: after every round of random vertex moves its bytes equal
//! `MeshFrame::quantise_in(..).encode()` of the same vertices, and the delta
//! it gives, applied to the frame taken before, gives those bytes. Taking a
//! revision again or an older one gives no delta; a position outside the
//! cube is refused and changes nothing.

use vsculpt_protocol::MeshFrame;
use vsculpt_protocol::mesh_delta::MeshDelta;
use vsculpt_protocol::mesh_patch::PatchedMeshFrame;

/// A seeded generator of numbers in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Positions, normals and triangles of a mesh.
type Mesh = (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[u32; 3]>);

/// A grid of n × n vertices on the unit square (z bumped), two triangles a cell.
fn grid(n: usize, rng: &mut Rng) -> Mesh {
    let mut p = Vec::new();
    let mut nn = Vec::new();
    for i in 0..n {
        for j in 0..n {
            p.push([i as f64 / n as f64, j as f64 / n as f64, 0.1 * rng.next()]);
            nn.push([rng.next() - 0.5, rng.next() - 0.5, 1.0]);
        }
    }
    let mut t = Vec::new();
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            let a = (i * n + j) as u32;
            let n = n as u32;
            t.push([a, a + n, a + n + 1]);
            t.push([a, a + n + 1, a + 1]);
        }
    }
    (p, nn, t)
}

const CUBE: ([f64; 3], f64) = ([-0.25, -0.25, -0.5], 1.5);

fn whole(rev: u64, p: &[[f64; 3]], n: &[[f64; 3]], t: &[[u32; 3]]) -> Vec<u8> {
    MeshFrame::quantise_in((7, 3, rev), 0, CUBE, p, n, t)
        .unwrap()
        .encode()
        .unwrap()
}

#[test]
fn patched_bytes_are_the_whole_frame_and_the_delta_gives_them_from_the_base() {
    let mut rng = Rng(0x09a7_c4ed);
    // 300 vertices: u16 indices; 40 000: u32.
    for n in [17usize, 200] {
        let (mut p, mut nn, t) = grid(n, &mut rng);
        let mut kept = PatchedMeshFrame::new((7, 3, 1), 0, CUBE, &p, &nn, &t).unwrap();
        let first = kept.take(1, 0);
        assert!(first.delta.is_none(), "no base yet");
        let mut held = first.frame.to_vec();
        assert_eq!(held, whole(1, &p, &nn, &t));
        for rev in 2..12u64 {
            // A random patch of vertices moves (some by less than a quantum).
            let centre = (rng.next() * (n * n) as f64) as usize;
            let radius = 1 + (rng.next() * 4.0) as usize;
            for v in centre.saturating_sub(radius * n)..(centre + radius * n).min(n * n) {
                let tiny = rng.next() < 0.2;
                let d = if tiny { 1e-7 } else { 0.01 };
                p[v] = p[v].map(|x| x + d * (rng.next() - 0.5));
                nn[v] = nn[v].map(|x| x + 0.1 * (rng.next() - 0.5));
                kept.set_vertex(v, p[v], nn[v]).unwrap();
            }
            let take = kept.take(rev, 0);
            let want = whole(rev, &p, &nn, &t);
            assert_eq!(take.frame, &want[..], "n {n} rev {rev}");
            let (base, bytes) = take.delta.expect("a delta");
            assert_eq!(base, rev - 1);
            assert!(bytes.len() < want.len());
            let made = MeshDelta::decode(&bytes)
                .unwrap()
                .apply(&MeshFrame::decode(&held).unwrap())
                .unwrap();
            held = made.encode().unwrap();
            assert_eq!(held, want, "n {n} rev {rev}: the delta applied");
        }
        // The same revision again, unchanged: the same bytes, no delta; the
        // next revision still has its delta.
        let again = kept.take(11, 0);
        assert!(again.delta.is_none());
        assert_eq!(again.frame, &held[..]);
        kept.set_vertex(0, [0.3, 0.3, 0.3], [0.0, 0.0, 1.0])
            .unwrap();
        assert_eq!(kept.take(12, 0).delta.map(|d| d.0), Some(11));
        // Changed and taken under a revision already handed out: no delta
        // from it, now or at the next take.
        kept.set_vertex(0, [0.4, 0.3, 0.3], [0.0, 0.0, 1.0])
            .unwrap();
        assert!(kept.take(12, 0).delta.is_none());
        kept.set_vertex(0, [0.5, 0.3, 0.3], [0.0, 0.0, 1.0])
            .unwrap();
        assert!(kept.take(13, 0).delta.is_none());
        kept.set_vertex(0, [0.6, 0.3, 0.3], [0.0, 0.0, 1.0])
            .unwrap();
        assert_eq!(kept.take(14, 0).delta.map(|d| d.0), Some(13));
        // Outside the cube, non-finite, or beyond the mesh: refused, nothing changed.
        let before = kept.take(14, 0).frame.to_vec();
        assert!(
            kept.set_vertex(0, [5.0, 0.0, 0.0], [0.0, 0.0, 1.0])
                .is_err()
        );
        assert!(
            kept.set_vertex(0, [f64::NAN, 0.0, 0.0], [0.0, 0.0, 1.0])
                .is_err()
        );
        assert!(kept.set_vertex(n * n, [0.0; 3], [0.0, 0.0, 1.0]).is_err());
        let after = kept.take(14, 0);
        assert!(after.delta.is_none());
        assert_eq!(after.frame, &before[..]);
    }
}
