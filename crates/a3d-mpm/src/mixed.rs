//! MPM-MIXED's per-step element smoothing, as the kernel's
//! `StressAndPorePressureSmoothening` (`MPMDYNConvPhase.FOR`): after the
//! MPs have moved, every element whose MPs all share one material gives each
//! of them the volume-weighted mean effective stress and pore pressure of its
//! MPs; elements holding MPs of two materials keep the MPs' own values. Then
//! S, k_r, the mixture's weight and p's force term follow from the mean p, as
//! the kernel updates them after the smoothing.

use super::particle::{Particle, settle_water};

/// Per-element sums, reused from step to step.
pub(super) struct ElementSums {
    volume: Vec<f64>,
    stress: Vec<[f64; 6]>,
    pwp: Vec<f64>,
    /// The solid-model slot (one per material) of the element's first MP.
    material: Vec<u32>,
    count: Vec<u32>,
    mixed: Vec<bool>,
}

impl ElementSums {
    pub(super) fn new(n_elements: usize) -> ElementSums {
        ElementSums {
            volume: vec![0.0; n_elements],
            stress: vec![[0.0; 6]; n_elements],
            pwp: vec![0.0; n_elements],
            material: vec![0; n_elements],
            count: vec![0; n_elements],
            mixed: vec![false; n_elements],
        }
    }

    /// Smooths the live MPs of `particles` in place.
    pub(super) fn smooth<const D: usize, const NC: usize>(
        &mut self,
        particles: &mut [Particle<D, NC>],
    ) {
        self.volume.fill(0.0);
        self.stress.fill([0.0; 6]);
        self.pwp.fill(0.0);
        self.count.fill(0);
        self.mixed.fill(false);
        for p in particles.iter().filter(|p| !p.lost) {
            let e = p.element as usize;
            if self.count[e] == 0 {
                self.material[e] = p.model;
            } else if self.material[e] != p.model {
                self.mixed[e] = true;
            }
            self.count[e] += 1;
            let v = p.volume;
            self.volume[e] += v;
            self.pwp[e] += v * p.pwp;
            for k in 0..6 {
                self.stress[e][k] += v * p.stress[k];
            }
        }
        for p in particles.iter_mut().filter(|p| !p.lost) {
            let e = p.element as usize;
            if !self.mixed[e] && self.count[e] > 1 {
                let v = self.volume[e];
                p.pwp = self.pwp[e] / v;
                for k in 0..6 {
                    p.stress[k] = self.stress[e][k] / v;
                }
            }
            settle_water(p);
        }
    }
}
