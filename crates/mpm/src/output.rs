//! What a run reports: per-step summaries (serialisable), the material-point
//! state as JSON columns, and VTK XML files for ParaView.

use std::io::{self, Write};

use serde::Serialize;

use crate::newton::NewtonInfo;
use crate::points::MaterialPoints;

/// Wall-clock seconds spent in each stage of a load step.
#[derive(Debug, Clone, Copy, Default, Serialize, serde::Deserialize, PartialEq)]
pub struct StepTimings {
    /// Grid reset: shape functions, active nodes, stiffness pattern, loads.
    pub grid: f64,
    /// Point loop: trial stress and tangent of every point, internal force.
    pub point_loop: f64,
    /// Tangent stiffness assembly (with constraints).
    pub assembly: f64,
    /// Sparse factorisation (symbolic analysis included on first use).
    pub factorisation: f64,
    /// Triangular solves.
    pub solve: f64,
    /// Moving points and probes, committing state.
    pub update: f64,
    pub total: f64,
}

impl std::ops::AddAssign<&StepTimings> for StepTimings {
    /// Sums stage by stage (timings of several steps).
    fn add_assign(&mut self, t: &StepTimings) {
        self.grid += t.grid;
        self.point_loop += t.point_loop;
        self.assembly += t.assembly;
        self.factorisation += t.factorisation;
        self.solve += t.solve;
        self.update += t.update;
        self.total += t.total;
    }
}

#[derive(Debug, Clone, Serialize, serde::Deserialize, PartialEq)]
pub struct ProbeReport {
    pub name: String,
    pub position: [f64; 2],
    pub displacement: [f64; 2],
}

/// Summary of one converged load step.
#[derive(Debug, Clone, Serialize, serde::Deserialize, PartialEq)]
pub struct StepReport {
    /// Counts from 1.
    pub step: usize,
    pub load_factor: f64,
    pub newton: NewtonInfo,
    pub timings: StepTimings,
    pub active_nodes: usize,
    /// Unconstrained degrees of freedom in the system.
    pub active_dofs: usize,
    pub probes: Vec<ProbeReport>,
    /// Force each support exerts on the body, in the order of the case's
    /// `supports`.
    pub reactions: Vec<[f64; 2]>,
    /// Resultant of the loads applied to the grid in this step (gravity,
    /// point loads and boundary loads on the converged boundary): at
    /// equilibrium the reactions add up to minus this, unless two grid
    /// supports hold the same component of a node (both then report its
    /// force). Zero in steps stored before it was reported.
    #[serde(default)]
    pub applied_load: [f64; 2],
}

/// Summary of a whole run.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct RunReport {
    pub points: usize,
    pub load_steps: usize,
    pub wall_seconds: f64,
    pub steps: Vec<StepReport>,
}

/// The material-point state as columns, for JSON.
#[derive(Debug, Clone, Serialize, serde::Deserialize, PartialEq)]
pub struct PointColumns {
    pub position: Vec<[f64; 2]>,
    pub displacement: Vec<[f64; 2]>,
    /// Cauchy stress `[xx, yy, xy, zz]`.
    pub stress: Vec<[f64; 4]>,
    /// Current volume `J V0`.
    pub volume: Vec<f64>,
    /// Volume ratio `J = det F`.
    pub jacobian: Vec<f64>,
    /// Index of the body the point belongs to.
    pub body: Vec<u32>,
}

impl PointColumns {
    pub fn new(mp: &MaterialPoints) -> Self {
        let n = mp.len();
        Self {
            position: mp.position.clone(),
            displacement: (0..n).map(|p| mp.displacement(p)).collect(),
            stress: mp
                .stress
                .iter()
                .map(|s| [s.plane[0], s.plane[1], s.plane[2], s.zz])
                .collect(),
            volume: (0..n).map(|p| mp.volume(p)).collect(),
            jacobian: (0..n).map(|p| mp.jacobian(p)).collect(),
            body: mp.material.clone(),
        }
    }
}

/// Writes the points as a VTK XML unstructured grid of vertex cells, with
/// raw appended binary data (little-endian, 64-bit block headers).
pub fn write_vtu(mut out: impl Write, cols: &PointColumns) -> io::Result<()> {
    let n = cols.position.len();
    let positions: Vec<f64> = cols
        .position
        .iter()
        .flat_map(|x| [x[0], x[1], 0.0])
        .collect();
    let displacement: Vec<f64> = cols
        .displacement
        .iter()
        .flat_map(|d| [d[0], d[1], 0.0])
        .collect();
    // VTK's symmetric-tensor order: XX, YY, ZZ, XY, YZ, XZ.
    let stress: Vec<f64> = cols
        .stress
        .iter()
        .flat_map(|s| [s[0], s[1], s[3], s[2], 0.0, 0.0])
        .collect();
    let body: Vec<f64> = cols.body.iter().map(|&b| b as f64).collect();
    let connectivity: Vec<i64> = (0..n as i64).collect();
    let offsets: Vec<i64> = (1..=n as i64).collect();
    let types = vec![1u8; n]; // VTK_VERTEX

    let mut blocks: Vec<Vec<u8>> = Vec::new();
    let mut xml = String::new();
    let mut offset = 0usize;
    let mut array = |xml: &mut String, name: &str, ty: &str, comps: usize, bytes: Vec<u8>| {
        xml.push_str(&format!(
            "        <DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"appended\" offset=\"{offset}\"/>\n"
        ));
        offset += 8 + bytes.len();
        blocks.push(bytes);
    };
    let f64s = |v: &[f64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let i64s = |v: &[i64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();

    xml.push_str("<?xml version=\"1.0\"?>\n");
    xml.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    xml.push_str("  <UnstructuredGrid>\n");
    xml.push_str(&format!(
        "    <Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">\n"
    ));
    xml.push_str("      <PointData Vectors=\"displacement\" Tensors=\"stress\">\n");
    array(&mut xml, "displacement", "Float64", 3, f64s(&displacement));
    array(&mut xml, "stress", "Float64", 6, f64s(&stress));
    array(&mut xml, "volume", "Float64", 1, f64s(&cols.volume));
    array(&mut xml, "jacobian", "Float64", 1, f64s(&cols.jacobian));
    array(&mut xml, "body", "Float64", 1, f64s(&body));
    xml.push_str("      </PointData>\n      <Points>\n");
    array(&mut xml, "position", "Float64", 3, f64s(&positions));
    xml.push_str("      </Points>\n      <Cells>\n");
    array(&mut xml, "connectivity", "Int64", 1, i64s(&connectivity));
    array(&mut xml, "offsets", "Int64", 1, i64s(&offsets));
    array(&mut xml, "types", "UInt8", 1, types);
    xml.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _");
    out.write_all(xml.as_bytes())?;
    for b in &blocks {
        out.write_all(&(b.len() as u64).to_le_bytes())?;
        out.write_all(b)?;
    }
    out.write_all(b"\n  </AppendedData>\n</VTKFile>\n")
}

/// Writes boundary polylines as a VTK XML poly-data file (ASCII), one line
/// cell per loop with its body index and whether it is a hole.
pub fn write_vtp(
    mut out: impl Write,
    boundaries: &[crate::boundary::BoundaryOutput],
) -> io::Result<()> {
    let n_points: usize = boundaries.iter().map(|b| b.polyline.len()).sum();
    writeln!(out, "<?xml version=\"1.0\"?>")?;
    writeln!(
        out,
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\">"
    )?;
    writeln!(out, "  <PolyData>")?;
    writeln!(
        out,
        "    <Piece NumberOfPoints=\"{n_points}\" NumberOfLines=\"{}\">",
        boundaries.len()
    )?;
    writeln!(
        out,
        "      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    for b in boundaries {
        for p in &b.polyline {
            writeln!(out, "{:e} {:e} 0", p[0], p[1])?;
        }
    }
    writeln!(out, "        </DataArray>\n      </Points>\n      <Lines>")?;
    writeln!(
        out,
        "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    )?;
    let mut first = 0;
    let mut offsets = Vec::with_capacity(boundaries.len());
    for b in boundaries {
        let ids: Vec<String> = (first..first + b.polyline.len())
            .map(|i| i.to_string())
            .collect();
        writeln!(out, "{}", ids.join(" "))?;
        first += b.polyline.len();
        offsets.push(first.to_string());
    }
    writeln!(out, "        </DataArray>")?;
    writeln!(
        out,
        "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n{}\n        </DataArray>",
        offsets.join(" ")
    )?;
    writeln!(out, "      </Lines>\n      <CellData>")?;
    let column = |f: &dyn Fn(&crate::boundary::BoundaryOutput) -> usize| {
        boundaries
            .iter()
            .map(|b| f(b).to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    writeln!(
        out,
        "        <DataArray type=\"Int32\" Name=\"body\" format=\"ascii\">\n{}\n        </DataArray>",
        column(&|b| b.body)
    )?;
    writeln!(
        out,
        "        <DataArray type=\"Int32\" Name=\"hole\" format=\"ascii\">\n{}\n        </DataArray>",
        column(&|b| b.hole as usize)
    )?;
    writeln!(
        out,
        "      </CellData>\n    </Piece>\n  </PolyData>\n</VTKFile>"
    )
}

/// A ParaView collection (`.pvd`) listing one file per load step, with the
/// load factor as its time value.
pub fn write_pvd(mut out: impl Write, files: &[(f64, String)]) -> io::Result<()> {
    writeln!(out, "<?xml version=\"1.0\"?>")?;
    writeln!(
        out,
        "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">"
    )?;
    writeln!(out, "  <Collection>")?;
    for (t, f) in files {
        writeln!(out, "    <DataSet timestep=\"{t}\" file=\"{f}\"/>")?;
    }
    writeln!(out, "  </Collection>\n</VTKFile>")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vtu_blocks_sit_at_their_declared_offsets() {
        let case = crate::Case::from_json(crate::examples::get("column").unwrap()).unwrap();
        let mp = MaterialPoints::from_case(&case);
        let mut buf = Vec::new();
        write_vtu(&mut buf, &PointColumns::new(&mp)).unwrap();
        let start = buf.windows(3).position(|w| w == b"  _").unwrap() + 3;
        let text = String::from_utf8_lossy(&buf[..start]);
        // The positions block: header says 3 * n * 8 bytes, and the first
        // coordinate read back is the first point's x.
        let off: usize = text
            .split("Name=\"position\"")
            .nth(1)
            .and_then(|s| s.split("offset=\"").nth(1))
            .and_then(|s| s.split('"').next())
            .unwrap()
            .parse()
            .unwrap();
        let at = start + off;
        let len = u64::from_le_bytes(buf[at..at + 8].try_into().unwrap()) as usize;
        assert_eq!(len, 3 * mp.len() * 8);
        let x0 = f64::from_le_bytes(buf[at + 8..at + 16].try_into().unwrap());
        assert_eq!(x0, mp.position[0][0]);
    }
}
