//! Energy bookkeeping for invariant checks: kinetic, gravitational, strain and spring energy.
use super::Simulation;
use crate::contact::ContactState;

/// Energies in J (per metre of thickness).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Energy {
    pub kinetic: f64,
    /// m·g·y of every free block's centroid (datum y = 0).
    pub gravity: f64,
    pub strain: f64,
    /// Penalty springs of closed contacts.
    pub springs: f64,
}

impl Energy {
    pub fn total(&self) -> f64 {
        self.kinetic + self.gravity + self.strain + self.springs
    }
}

impl Simulation {
    /// Current energies of the free blocks and contact springs.
    pub fn energy(&self) -> Energy {
        let mut e = Energy::default();
        for (f, st) in self.state.states.iter().enumerate() {
            let b = self.state.dofs.block_of[f];
            let g = &self.state.geoms[b];
            let rho = self.state.scene.materials[self.state.scene.blocks[b].material].density;
            let nd = self.state.dofs.ndof[f];
            let m = g.mass_matrix(rho);
            let mut v = st.vel;
            for k in nd..6 {
                v[k] = 0.0;
            }
            e.kinetic += 0.5 * (v.transpose() * m * v)[(0, 0)];
            e.gravity += rho * g.moments.area * self.state.scene.gravity * g.centroid.y;
            if nd == 6 {
                // ½·A·σᵀ·C⁻¹·σ
                if let Some(inv) = self.state.elastic_inverse(f) {
                    e.strain +=
                        0.5 * g.moments.area * (st.stress.transpose() * inv * st.stress)[(0, 0)];
                }
            }
        }
        for c in &self.state.contacts.contacts {
            match c.state {
                ContactState::Open => {}
                ContactState::Locked => {
                    e.springs += 0.5 * self.stepper.springs.normal * c.gap.min(0.0).powi(2)
                        + 0.5 * self.stepper.springs.shear * (c.s0 + c.slip).powi(2)
                }
                ContactState::Sliding { .. } => {
                    e.springs += 0.5 * self.stepper.springs.normal * c.gap.min(0.0).powi(2)
                }
            }
        }
        e
    }
}
