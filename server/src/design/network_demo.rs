//! The styling-curve demo (paper 004's third example): the front half of a
//! bottle drawn with nine styling curves — three rings, four meridians and
//! two shoulder diagonals — enclosing six faces, one of them five-sided
//! (the label face), as a network part, alone in a design (`POST
//! /api/designs` with `"template": "bottle"`).

use super::doc::{DOC_FORMAT, DesignDoc};
use super::error::{CommandError, ErrorKind};
use super::network_engine::NetworkEngine;
use super::part::{CurveDoc, NetworkPart, PALETTE, PartBody, PartDoc};

/// The bottle network part (the kernel's `network::demo::bottle` curves).
pub fn bottle_part() -> Result<NetworkPart, CommandError> {
    let net = vsculpt_kernel::network::demo::bottle()
        .map_err(|e| CommandError::new(ErrorKind::InvalidValue, e.to_string()))?;
    let part = NetworkPart {
        curves: net
            .curves()
            .iter()
            .map(|c| CurveDoc {
                degree: c.degree(),
                knots: c.knots().knots().to_vec(),
                points: c.points().iter().map(|p| p.to_array()).collect(),
            })
            .collect(),
        tolerance: net.options().tolerance,
        up: net.options().up.to_array(),
        faired: Vec::new(),
        ribbons: Default::default(),
        icons: Vec::new(),
    };
    // Built once as the server will build it (faces found, patches made).
    NetworkEngine::build(&part)?;
    Ok(part)
}

/// A design named `name` holding the bottle network as its one part.
pub fn bottle_design(name: &str) -> Result<DesignDoc, CommandError> {
    let doc = DesignDoc {
        format: DOC_FORMAT,
        name: name.to_string(),
        parts: vec![PartDoc {
            id: 1,
            name: "bottle".into(),
            visible: true,
            locked: false,
            colour: PALETTE[1].to_string(),
            body: PartBody::Network(bottle_part()?),
        }],
        relations: Vec::new(),
        next_icon: 1,
        next_part: 2,
        next_relation: 1,
    };
    doc.validate()?;
    Ok(doc)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::DesignModel;

    #[test]
    fn the_bottle_design_loads_and_sends_one_mesh_frame() {
        let doc = bottle_design("bottle").unwrap();
        let m = DesignModel::load(&doc).unwrap();
        assert_eq!(m.to_doc(), doc, "a reload is exact");
        let set = m.geometry_set(1, 0);
        assert_eq!(set.parts.len(), 1);
        let frame = vsculpt_protocol::MeshFrame::decode(&set.parts[&1].frame).unwrap();
        assert!(frame.triangles.len() > 1000, "{}", frame.triangles.len());
    }
}
