//! VTK XML files for ParaView: the points as an unstructured grid, the
//! boundary curves as polylines, and the `.pvd` series that steps through
//! them.

use std::io::{self, Write};

use crate::report::{PointColumns, SolidPointColumns};

/// Writes the points as a VTK XML unstructured grid of vertex cells, with
/// raw appended binary data (little-endian, 64-bit block headers).
pub fn write_vtu(out: impl Write, cols: &PointColumns) -> io::Result<()> {
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
    write_columns(
        out,
        &VtuColumns {
            n: cols.position.len(),
            positions: &positions,
            displacement: &displacement,
            stress: &stress,
            volume: &cols.volume,
            jacobian: &cols.jacobian,
            body: &cols.body,
            plastic_strain: &cols.plastic_strain,
            yielding: &cols.yielding,
        },
    )
}

/// Writes a 3D run's points as [`write_vtu`] writes a plane-strain run's.
pub fn write_solid_vtu(out: impl Write, cols: &SolidPointColumns) -> io::Result<()> {
    write_columns(
        out,
        &VtuColumns {
            n: cols.position.len(),
            positions: cols.position.as_flattened(),
            displacement: cols.displacement.as_flattened(),
            stress: cols.stress.as_flattened(),
            volume: &cols.volume,
            jacobian: &cols.jacobian,
            body: &cols.body,
            plastic_strain: &cols.plastic_strain,
            yielding: &cols.yielding,
        },
    )
}

/// The points' columns as a VTU file holds them: vectors of three
/// components, the stress of six (VTK's order), the rest one; an empty
/// column is left out.
struct VtuColumns<'a> {
    n: usize,
    positions: &'a [f64],
    displacement: &'a [f64],
    stress: &'a [f64],
    volume: &'a [f64],
    jacobian: &'a [f64],
    body: &'a [u32],
    plastic_strain: &'a [f64],
    yielding: &'a [bool],
}

fn write_columns(mut out: impl Write, cols: &VtuColumns<'_>) -> io::Result<()> {
    let n = cols.n;
    let connectivity: Vec<i64> = (0..n as i64).collect();
    let offsets: Vec<i64> = (1..=n as i64).collect();
    let types = vec![1u8; n]; // VTK_VERTEX

    let mut blocks: Vec<Vec<u8>> = Vec::new();
    let mut xml = String::new();
    let mut offset = 0usize;
    // A column the case left out (empty) is not written.
    let mut array = |xml: &mut String, name: &str, ty: &str, comps: usize, bytes: Vec<u8>| {
        if bytes.is_empty() && n > 0 {
            return;
        }
        xml.push_str(&format!(
            "        <DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"appended\" offset=\"{offset}\"/>\n"
        ));
        offset += 4 + bytes.len();
        blocks.push(bytes);
    };
    let f64s = |v: &[f64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    // The body index and the yield flag as Float64, as ParaView colours by.
    let body: Vec<f64> = cols.body.iter().map(|&b| f64::from(b)).collect();
    let yielding: Vec<f64> = (cols.yielding.iter())
        .map(|&y| if y { 1.0 } else { 0.0 })
        .collect();
    let i64s = |v: &[i64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();

    xml.push_str("<?xml version=\"1.0\"?>\n");
    xml.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt32\">\n");
    xml.push_str("  <UnstructuredGrid>\n");
    xml.push_str(&format!(
        "    <Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">\n"
    ));
    let vectors = if cols.displacement.is_empty() {
        ""
    } else {
        " Vectors=\"displacement\""
    };
    let tensors = if cols.stress.is_empty() {
        ""
    } else {
        " Tensors=\"stress\""
    };
    xml.push_str(&format!("      <PointData{vectors}{tensors}>\n"));
    array(
        &mut xml,
        "displacement",
        "Float64",
        3,
        f64s(cols.displacement),
    );
    array(&mut xml, "stress", "Float64", 6, f64s(cols.stress));
    array(&mut xml, "volume", "Float64", 1, f64s(cols.volume));
    array(&mut xml, "jacobian", "Float64", 1, f64s(cols.jacobian));
    array(&mut xml, "body", "Float64", 1, f64s(&body));
    array(
        &mut xml,
        "plastic_strain",
        "Float64",
        1,
        f64s(cols.plastic_strain),
    );
    array(&mut xml, "yielding", "Float64", 1, f64s(&yielding));
    xml.push_str("      </PointData>\n      <Points>\n");
    array(&mut xml, "position", "Float64", 3, f64s(cols.positions));
    xml.push_str("      </Points>\n      <Cells>\n");
    array(&mut xml, "connectivity", "Int64", 1, i64s(&connectivity));
    array(&mut xml, "offsets", "Int64", 1, i64s(&offsets));
    array(&mut xml, "types", "UInt8", 1, types);
    xml.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _");
    out.write_all(xml.as_bytes())?;
    for b in &blocks {
        // UInt32 block headers: meshio (5.3) misreads UInt64 ones; 4 GiB an
        // array is some 170 million points.
        let len = u32::try_from(b.len())
            .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "a VTU array over 4 GiB"))?;
        out.write_all(&len.to_le_bytes())?;
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

/// Quads a side of each surface cell in [`write_surface_vtp`].
pub const SURFACE_SAMPLES_PER_CELL: usize = 4;

/// A 3D run's surfaces as VTP polygons: each Bezier cell evaluated on a
/// grid of [`SURFACE_SAMPLES_PER_CELL`] quads a side, with the body and
/// the face patch of each quad.
pub fn write_surface_vtp(
    mut out: impl Write,
    surfaces: &[crate::boundary::face_patches::SurfaceOutput],
) -> io::Result<()> {
    let m = SURFACE_SAMPLES_PER_CELL;
    let cells: usize = surfaces.iter().map(|s| s.cells[0] * s.cells[1]).sum();
    let (n_points, n_polys) = (cells * (m + 1) * (m + 1), cells * m * m);
    writeln!(out, "<?xml version=\"1.0\"?>")?;
    writeln!(
        out,
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\">"
    )?;
    writeln!(out, "  <PolyData>")?;
    writeln!(
        out,
        "    <Piece NumberOfPoints=\"{n_points}\" NumberOfPolys=\"{n_polys}\">"
    )?;
    writeln!(
        out,
        "      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    for s in surfaces {
        for l in 0..s.cells[1] {
            for k in 0..s.cells[0] {
                for b in 0..=m {
                    for a in 0..=m {
                        let x = s.point(k, l, a as f64 / m as f64, b as f64 / m as f64);
                        writeln!(out, "{:e} {:e} {:e}", x[0], x[1], x[2])?;
                    }
                }
            }
        }
    }
    writeln!(out, "        </DataArray>\n      </Points>\n      <Polys>")?;
    writeln!(
        out,
        "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    )?;
    for cell in 0..cells {
        let first = cell * (m + 1) * (m + 1);
        for b in 0..m {
            for a in 0..m {
                let at = |a: usize, b: usize| first + a + (m + 1) * b;
                writeln!(
                    out,
                    "{} {} {} {}",
                    at(a, b),
                    at(a + 1, b),
                    at(a + 1, b + 1),
                    at(a, b + 1)
                )?;
            }
        }
    }
    writeln!(out, "        </DataArray>")?;
    writeln!(
        out,
        "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">"
    )?;
    for q in 1..=n_polys {
        write!(out, "{} ", 4 * q)?;
    }
    writeln!(
        out,
        "\n        </DataArray>\n      </Polys>\n      <CellData>"
    )?;
    for (name, value) in [("body", 0), ("patch", 1)] {
        writeln!(
            out,
            "        <DataArray type=\"Int32\" Name=\"{name}\" format=\"ascii\">"
        )?;
        for (i, s) in surfaces.iter().enumerate() {
            let v = if value == 0 { s.body } else { i };
            for _ in 0..s.cells[0] * s.cells[1] * m * m {
                write!(out, "{v} ")?;
            }
        }
        writeln!(out, "\n        </DataArray>")?;
    }
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
        let case = crate::Case::from_json(crate::case::builtin::get("column").unwrap()).unwrap();
        let mp = crate::Simulation::new(&case).unwrap().points;
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
        let len = u32::from_le_bytes(buf[at..at + 4].try_into().unwrap()) as usize;
        assert_eq!(len, 3 * mp.len() * 8);
        let x0 = f64::from_le_bytes(buf[at + 4..at + 12].try_into().unwrap());
        assert_eq!(x0, mp.position[0][0]);
    }
}
