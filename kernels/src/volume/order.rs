//! The order of a volume's samples in memory as the samplers read them (`volume.order`, issue 43):
//! row-major (x fastest, the source's own order), in Morton order (the smallest power-of-two box
//! holding the volume, its axes' bits interleaved while each has some:
//! `structures::voxel::morton::Interleave`), or in 4³ or 8³ tiles of row-major voxels laid out
//! row-major (the bricking a GPU texture or a CPU ray caster uses: Grimm, Bruckner et al. 2004).
//! Every order holds the same samples, so every image is the same bit for bit; what changes is
//! which voxels share a cache line or page, against the cost of computing an address: one
//! multiply-add row-major, shifts and masks for tiles, a bit deposit per coordinate in Morton
//! order (`pdep` where the CPU has BMI2, byte tables otherwise). Morton and tiles pad the volume
//! (zeros, never read) to the power-of-two box or to whole tiles. The structures over the volume
//! (bricks, trees) are built from its row-major samples and are the same in every order.

use std::borrow::Cow;

use scenes::volume::{Samples, Volume};
use structures::voxel::morton::{Interleave, Morton};

/// Which order (`volume.order`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VoxelOrder {
    Linear,
    Morton,
    /// Tiles of `2^shift` voxels a side, row-major inside and row-major among themselves.
    Tiles {
        shift: u32,
    },
}

impl VoxelOrder {
    pub const NAMES: [(&'static str, VoxelOrder); 4] = [
        ("linear", VoxelOrder::Linear),
        ("morton", VoxelOrder::Morton),
        ("tile4", VoxelOrder::Tiles { shift: 2 }),
        ("tile8", VoxelOrder::Tiles { shift: 3 }),
    ];

    pub fn name(self) -> &'static str {
        Self::NAMES.iter().find(|(_, o)| *o == self).map_or("linear", |(n, _)| n)
    }

    /// The order called `name`.
    pub fn parse(name: &str) -> Result<Self, String> {
        Self::NAMES.iter().find(|(n, _)| *n == name).map(|&(_, o)| o).ok_or_else(|| {
            let names: Vec<&str> = Self::NAMES.iter().map(|(n, _)| *n).collect();
            format!("volume.order '{name}' is not one of {}", names.join(", "))
        })
    }

    /// Samples a volume of `dims` voxels takes in this order, the padding included: Morton order
    /// pads each axis to a power of two, tiles to a whole tile. Known before any copy is made (a
    /// memory budget's check); a store's [`VoxelStore::padded_len`] is this.
    pub fn padded_len(self, dims: [u32; 3]) -> u64 {
        let padded = |d: u32| -> u64 {
            match self {
                VoxelOrder::Linear => u64::from(d),
                VoxelOrder::Morton => u64::from(d.next_power_of_two()),
                VoxelOrder::Tiles { shift } => u64::from(d.div_ceil(1 << shift)) << shift,
            }
        };
        dims.iter().map(|&d| padded(d)).product()
    }
}

/// How an index is computed, with what it needs.
#[derive(Clone, Debug)]
enum Addressing {
    Linear { dims: [usize; 3] },
    Morton { interleave: Interleave, encoder: Morton },
    Tiles { shift: u32, tiles: [usize; 3] },
}

/// A volume's samples in one [`VoxelOrder`]: borrowed from the volume row-major, a reordered copy
/// otherwise.
#[derive(Clone, Debug)]
pub struct VoxelStore<'a> {
    order: VoxelOrder,
    addressing: Addressing,
    samples: Cow<'a, Samples>,
}

impl<'a> VoxelStore<'a> {
    /// The volume's own samples, row-major (no copy).
    pub fn linear(volume: &'a Volume) -> Self {
        VoxelStore {
            order: VoxelOrder::Linear,
            addressing: Addressing::Linear { dims: volume.dims.map(|d| d as usize) },
            samples: Cow::Borrowed(&volume.samples),
        }
    }

    /// The volume's samples copied into `order` (Morton indices by `encoder`); refused where the
    /// padded volume would need more than 2³² indices (the GPU kernel's 32-bit index).
    pub fn new(volume: &'a Volume, order: VoxelOrder, encoder: Morton) -> Result<Self, String> {
        let addressing = match order {
            VoxelOrder::Linear => return Ok(Self::linear(volume)),
            VoxelOrder::Morton => Addressing::Morton {
                interleave: Interleave::new(volume.dims)
                    .ok_or_else(|| format!("{:?} voxels pad to more than 2^32 in Morton order", volume.dims))?,
                encoder,
            },
            VoxelOrder::Tiles { shift } => {
                if order.padded_len(volume.dims) > 1 << 32 {
                    return Err(format!("{:?} voxels pad to more than 2^32 in tiles", volume.dims));
                }
                Addressing::Tiles { shift, tiles: volume.dims.map(|d| d.div_ceil(1 << shift) as usize) }
            }
        };
        let mut store = VoxelStore { order, addressing, samples: Cow::Owned(Samples::U8(Vec::new())) };
        let len = store.padded_len();
        let dims = volume.dims;
        macro_rules! reorder {
            ($src:expr, $variant:ident) => {{
                let mut out = vec![Default::default(); len];
                let mut i = 0;
                for z in 0..dims[2] {
                    for y in 0..dims[1] {
                        for x in 0..dims[0] {
                            out[store.index(x, y, z)] = $src[i];
                            i += 1;
                        }
                    }
                }
                Samples::$variant(out)
            }};
        }
        store.samples = Cow::Owned(match &volume.samples {
            Samples::U8(v) => reorder!(v, U8),
            Samples::U16(v) => reorder!(v, U16),
            Samples::F32(v) => reorder!(v, F32),
        });
        Ok(store)
    }

    pub fn order(&self) -> VoxelOrder {
        self.order
    }

    /// The Morton encoder, in Morton order.
    pub fn encoder(&self) -> Option<Morton> {
        match &self.addressing {
            Addressing::Morton { encoder, .. } => Some(*encoder),
            _ => None,
        }
    }

    /// Samples stored, the padding included.
    pub fn padded_len(&self) -> usize {
        match &self.addressing {
            Addressing::Linear { dims } => dims.iter().product(),
            Addressing::Morton { interleave, .. } => interleave.len() as usize,
            Addressing::Tiles { shift, tiles } => tiles.iter().product::<usize>() << (3 * shift),
        }
    }

    /// The samples as stored (the GPU uploads them).
    pub fn samples(&self) -> &Samples {
        &self.samples
    }

    /// Where voxel (x, y, z) is stored.
    #[inline(always)]
    pub fn index(&self, x: u32, y: u32, z: u32) -> usize {
        match &self.addressing {
            Addressing::Linear { dims } => x as usize + dims[0] * (y as usize + dims[1] * z as usize),
            Addressing::Morton { interleave, encoder } => interleave.encode(*encoder, [x, y, z]) as usize,
            Addressing::Tiles { shift, tiles } => {
                let (s, m) = (*shift, (1u32 << shift) - 1);
                let tile = (x >> s) as usize + tiles[0] * ((y >> s) as usize + tiles[1] * (z >> s) as usize);
                tile << (3 * s) | ((x & m) | (y & m) << s | (z & m) << (2 * s)) as usize
            }
        }
    }

    /// Voxel (x, y, z) as `f32`: `Volume::value` in this order.
    #[inline(always)]
    pub fn value(&self, x: u32, y: u32, z: u32) -> f32 {
        self.samples.get(self.index(x, y, z))
    }

    /// The trilinear interpolation by `f` of the cell at `i` (its far corners clamped to `last`),
    /// in `super::interpolate`'s order of operations. The cell's first corner is addressed once;
    /// the others add a step per axis. A step is one row-major stride, one within a tile (or the
    /// jump to the next tile at its face), or a Morton index's dilated increment, because every
    /// order's index is a sum of one term per axis. On an axis of one voxel (`last` 0) the far
    /// corner is the near one. The order and the sample type are matched once per sample:
    /// matched per corner, the row-major dense marcher ran at 0.55–0.63× its speed before the
    /// store existed, and addressing each corner afresh cost Morton and tiles another 1.1–1.3×
    /// (mri-ch2better and fog@dragon:512 at 1024², 2 threads).
    #[inline(always)]
    pub fn trilinear(&self, i: [u32; 3], f: [f32; 3], last: [u32; 3]) -> f32 {
        let base = self.index(i[0], i[1], i[2]);
        let up = |a: usize, step: usize| if last[a] == 0 { 0 } else { step };
        let steps = match &self.addressing {
            Addressing::Linear { dims } => [up(0, 1), up(1, dims[0]), up(2, dims[0] * dims[1])],
            Addressing::Morton { interleave, .. } => {
                let masks = interleave.masks();
                let b = base as u32;
                std::array::from_fn(|a| {
                    let next = Interleave::step(b, masks[a], interleave.step_addend(a, 1));
                    up(a, next.wrapping_sub(b) as usize)
                })
            }
            Addressing::Tiles { shift, tiles } => {
                let s = *shift;
                let m = (1u32 << s) - 1;
                // Across the tile's far face: the next tile's first layer (the tile index's
                // stride, less the in-tile coordinate's `m`).
                let tile_stride = [1, tiles[0], tiles[0] * tiles[1]];
                std::array::from_fn(|a| {
                    let inner = 1usize << (s as usize * a);
                    let step = if i[a] & m != m { inner } else { (tile_stride[a] << (3 * s)) - m as usize * inner };
                    up(a, step)
                })
            }
        };
        let at = |dx: u32, dy: u32, dz: u32| {
            base.wrapping_add(steps[0] * dx as usize)
                .wrapping_add(steps[1] * dy as usize)
                .wrapping_add(steps[2] * dz as usize)
        };
        match &*self.samples {
            Samples::U8(v) => super::interpolate(f, |dx, dy, dz| f32::from(v[at(dx, dy, dz)])),
            Samples::U16(v) => super::interpolate(f, |dx, dy, dz| f32::from(v[at(dx, dy, dz)])),
            Samples::F32(v) => super::interpolate(f, |dx, dy, dz| v[at(dx, dy, dz)]),
        }
    }

    /// The words the GPU kernel's addressing reads (volume.wgsl's `M_ORDER` and the three after
    /// it): 0 row-major; 1 and each axis's Morton mask; 2 and the tile shift and tiles along x
    /// and y.
    pub fn gpu_words(&self) -> [u32; 4] {
        match &self.addressing {
            Addressing::Linear { .. } => [0; 4],
            Addressing::Morton { interleave, .. } => {
                let [mx, my, mz] = interleave.masks();
                [1, mx, my, mz]
            }
            Addressing::Tiles { shift, tiles } => [2, *shift, tiles[0] as u32, tiles[1] as u32],
        }
    }
}
