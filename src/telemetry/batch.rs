//! Component batches built straight from weft's arrays.
//!
//! Rerun serialises a batch of 3-vectors (positions, normals, arrows)
//! component by component, through an iterator per value. A frame at level
//! `full` logs a dozen such batches of every particle, so here they are
//! built as Rerun stores them (a fixed-size list of three `f32` per value)
//! from one copy of the slice:
//!
//! ```ignore
//! rec.log("world/points", &batch::points(&x).with_radii([0.01]))?;
//! ```

use std::sync::Arc;

use glam::Vec3;
use rerun::external::arrow::array::{FixedSizeListArray, Float32Array};
use rerun::external::arrow::datatypes::{DataType, Field};
use rerun::{ComponentDescriptor, SerializedComponentBatch};

/// `values` as the batch of a 3-vector component (`Position3D`,
/// `Vector3D`, …) described by `descriptor`.
pub fn vec3s(values: &[Vec3], descriptor: ComponentDescriptor) -> SerializedComponentBatch {
    let mut flat = Vec::with_capacity(3 * values.len());
    for v in values {
        flat.extend_from_slice(&v.to_array());
    }
    flat_vec3s(flat, descriptor)
}

/// The batch of a 3-vector component from its coordinates, three a value.
fn flat_vec3s(flat: Vec<f32>, descriptor: ComponentDescriptor) -> SerializedComponentBatch {
    debug_assert!(flat.len().is_multiple_of(3));
    let flat = Float32Array::from(flat);
    let item = Arc::new(Field::new("item", DataType::Float32, false));
    let array = FixedSizeListArray::new(item, 3, Arc::new(flat), None);
    SerializedComponentBatch::new(Arc::new(array), descriptor)
}

/// Points at `positions`, nothing else set.
pub fn points(positions: &[Vec3]) -> rerun::Points3D {
    let mut points = rerun::Points3D::update_fields();
    points.positions = Some(vec3s(positions, rerun::Points3D::descriptor_positions()));
    points
}

/// Arrows `scale · v` from `origins[k]` for the vectors `v = vectors[k]`
/// that `keep`, each at most `longest` long (a longer one keeps its
/// direction), nothing else set, in one pass over both.
pub fn arrows(
    origins: &[Vec3],
    vectors: &[Vec3],
    scale: f32,
    longest: f32,
    keep: impl Fn(Vec3) -> bool,
) -> rerun::Arrows3D {
    let n = 3 * origins.len().min(vectors.len());
    let (mut from, mut along) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for (o, v) in origins.iter().zip(vectors) {
        if keep(*v) {
            from.extend_from_slice(&o.to_array());
            let arrow = *v * scale;
            // Compared squared: no square root for the arrows that fit.
            let arrow = if arrow.length_squared() > longest * longest {
                arrow * (longest / arrow.length())
            } else {
                arrow
            };
            along.extend_from_slice(&arrow.to_array());
        }
    }
    let mut arrows = rerun::Arrows3D::update_fields();
    arrows.vectors = Some(flat_vec3s(along, rerun::Arrows3D::descriptor_vectors()));
    arrows.origins = Some(flat_vec3s(from, rerun::Arrows3D::descriptor_origins()));
    arrows
}

/// A mesh's vertex positions and normals, its other fields left as they
/// were logged.
pub fn mesh_update(positions: &[Vec3], normals: &[Vec3]) -> rerun::Mesh3D {
    let mut mesh = rerun::Mesh3D::update_fields();
    mesh.vertex_positions = Some(vec3s(
        positions,
        rerun::Mesh3D::descriptor_vertex_positions(),
    ));
    mesh.vertex_normals = Some(vec3s(normals, rerun::Mesh3D::descriptor_vertex_normals()));
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;
    use rerun::external::arrow::array::Array;

    #[test]
    fn batches_match_rerun_s_own_serialisation() {
        let v = [Vec3::new(1.0, -2.0, 3.5), Vec3::ZERO, Vec3::splat(f32::MAX)];
        let ours = vec3s(&v, rerun::Points3D::descriptor_positions());
        let theirs = rerun::Points3D::new(v)
            .positions
            .expect("positions are serialised");
        assert_eq!(ours.descriptor, theirs.descriptor);
        assert_eq!(ours.array.data_type(), theirs.array.data_type());
        assert_eq!(ours.array.to_data(), theirs.array.to_data());
    }

    #[test]
    fn archetypes_match_rerun_s_own() {
        let (o, v) = ([Vec3::X, Vec3::Y], [Vec3::Z, -Vec3::Z]);
        assert_eq!(points(&o), rerun::Points3D::new(o));
        assert_eq!(
            arrows(&o, &v, 1.0, f32::INFINITY, |_| true),
            rerun::Arrows3D::from_vectors(v).with_origins(o)
        );
        assert_eq!(
            arrows(&o, &v, 2.0, f32::INFINITY, |v| v.z > 0.0),
            rerun::Arrows3D::from_vectors([2.0 * Vec3::Z]).with_origins([Vec3::X])
        );
        // Longer than `longest`: shortened to it, the direction kept.
        assert_eq!(
            arrows(&o, &v, 2.0, 1.5, |_| true),
            rerun::Arrows3D::from_vectors([1.5 * Vec3::Z, -1.5 * Vec3::Z]).with_origins(o)
        );
        assert_eq!(
            arrows(&o, &v, 2.0, f32::INFINITY, |_| false),
            rerun::Arrows3D::from_vectors(Vec::<Vec3>::new()).with_origins(Vec::<Vec3>::new())
        );
        assert_eq!(
            mesh_update(&o, &v),
            rerun::Mesh3D::update_fields()
                .with_vertex_positions(o)
                .with_vertex_normals(v)
        );
    }
}
