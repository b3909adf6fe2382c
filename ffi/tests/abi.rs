//! ABI checks against the linked Embree library: struct layouts, and an instanced hit written
//! by the library into a ray-hit guarded by canaries. A header/library mismatch (the crates.io
//! `embree4-sys` 4.2 headers against a 4.3+ library) makes the library write past
//! `RTCRayHit`, which the canaries catch.

use std::mem::{offset_of, size_of};
use std::ptr;

use embree4_sys::*;

#[test]
fn ray_layout_matches_embree_abi() {
    assert_eq!(size_of::<RTCRay>(), 48);
    assert_eq!(offset_of!(RTCRay, tfar), 32);
    assert_eq!(offset_of!(RTCRayHit, hit), 48);
    let levels = RTC_MAX_INSTANCE_LEVEL_COUNT as usize;
    // Ng, u, v, primID, geomID, then instID[levels] (and instPrimID[levels] with instance
    // arrays), padded to 16 bytes.
    #[cfg(embree_instance_array)]
    let hit_fields = 7 * 4 + 2 * 4 * levels;
    #[cfg(not(embree_instance_array))]
    let hit_fields = 7 * 4 + 4 * levels;
    assert_eq!(size_of::<RTCHit>(), hit_fields.next_multiple_of(16));
    assert_eq!(RAY_HIT_SIZE, 48 + size_of::<RTCHit>());
}

#[cfg(embree_instance_array)]
#[test]
fn hit_has_instance_primitive_ids_when_configured() {
    assert_eq!(
        offset_of!(RTCHit, instPrimID),
        offset_of!(RTCHit, instID) + 4 * RTC_MAX_INSTANCE_LEVEL_COUNT as usize
    );
}

const CANARY: u32 = 0xDEAD_BEEF;

#[repr(C, align(16))]
struct Guarded {
    before: [u32; 16],
    rayhit: RTCRayHit,
    after: [u32; 32],
}

/// A single triangle in the z = 0 plane: (0,0,0), (1,0,0), (0,1,0).
unsafe fn triangle_scene(device: RTCDevice) -> RTCScene {
    // SAFETY (whole fn): valid device; buffers returned by Embree have the requested sizes.
    unsafe {
        let geom = rtcNewGeometry(device, RTCGeometryType::RTC_GEOMETRY_TYPE_TRIANGLE);
        let vb = rtcSetNewGeometryBuffer(
            geom,
            RTCBufferType::RTC_BUFFER_TYPE_VERTEX,
            0,
            RTCFormat::RTC_FORMAT_FLOAT3,
            12,
            3,
        ) as *mut [f32; 3];
        vb.write([0.0, 0.0, 0.0]);
        vb.add(1).write([1.0, 0.0, 0.0]);
        vb.add(2).write([0.0, 1.0, 0.0]);
        let ib = rtcSetNewGeometryBuffer(
            geom,
            RTCBufferType::RTC_BUFFER_TYPE_INDEX,
            0,
            RTCFormat::RTC_FORMAT_UINT3,
            12,
            1,
        ) as *mut [u32; 3];
        ib.write([0, 1, 2]);
        rtcCommitGeometry(geom);
        let scene = rtcNewScene(device);
        rtcAttachGeometry(scene, geom);
        rtcReleaseGeometry(geom);
        rtcCommitScene(scene);
        scene
    }
}

#[test]
fn instanced_hit_reports_inst_id_and_leaves_neighbours_intact() {
    // SAFETY: straight-line use of the C API with valid handles, released at the end; the
    // ray-hit lives in a repr(C) struct whose canaries detect any out-of-bounds write.
    unsafe {
        let device = rtcNewDevice(ptr::null());
        assert!(!device.is_null());
        let prototype = triangle_scene(device);
        let top = rtcNewScene(device);
        // Occupy id 0 with another instance, so the hit must report instID 1.
        for translate_x in [100.0f32, 0.0] {
            let inst = rtcNewGeometry(device, RTCGeometryType::RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(inst, prototype);
            let xf: [f32; 12] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, translate_x, 0.0, 2.0];
            rtcSetGeometryTransform(inst, 0, RTCFormat::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xf.as_ptr().cast());
            rtcCommitGeometry(inst);
            rtcAttachGeometry(top, inst);
            rtcReleaseGeometry(inst);
        }
        rtcCommitScene(top);
        assert_eq!(rtcGetDeviceError(device), RTCError::RTC_ERROR_NONE);

        let mut g = Guarded { before: [CANARY; 16], rayhit: RTCRayHit::default(), after: [CANARY; 32] };
        g.rayhit.ray = RTCRay {
            org_x: 0.25,
            org_y: 0.25,
            org_z: 0.0,
            dir_z: 1.0,
            tfar: f32::INFINITY,
            mask: u32::MAX,
            ..Default::default()
        };
        g.rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        g.rayhit.hit.instID = [RTC_INVALID_GEOMETRY_ID; RTC_MAX_INSTANCE_LEVEL_COUNT as usize];
        rtcIntersect1(top, &mut g.rayhit, ptr::null_mut());

        assert!(g.before.iter().all(|&c| c == CANARY), "Embree wrote before RTCRayHit");
        assert!(
            g.after.iter().all(|&c| c == CANARY),
            "Embree wrote past RTCRayHit: headers do not match the library"
        );
        let hit = &g.rayhit.hit;
        assert_eq!(hit.instID[0], 1);
        assert_eq!(hit.geomID, 0);
        assert_eq!(hit.primID, 0);
        assert!((g.rayhit.ray.tfar - 2.0).abs() < 1e-6, "t = {}", g.rayhit.ray.tfar);
        assert!((hit.u - 0.25).abs() < 1e-6 && (hit.v - 0.25).abs() < 1e-6);

        rtcReleaseScene(top);
        rtcReleaseScene(prototype);
        rtcReleaseDevice(device);
    }
}

#[test]
fn packet_layouts_match_embree_abi() {
    // Structure-of-arrays: RTCRayN is 12 arrays of N floats/uints; the packets need 16-, 32-
    // and 64-byte alignment, which the headers' RTC_ALIGN gives the generated types.
    assert_eq!((size_of::<RTCRay4>(), std::mem::align_of::<RTCRay4>()), (12 * 4 * 4, 16));
    assert_eq!((size_of::<RTCRay8>(), std::mem::align_of::<RTCRay8>()), (12 * 8 * 4, 32));
    assert_eq!((size_of::<RTCRay16>(), std::mem::align_of::<RTCRay16>()), (12 * 16 * 4, 64));
    let levels = RTC_MAX_INSTANCE_LEVEL_COUNT as usize;
    #[cfg(embree_instance_array)]
    let hit_arrays = 7 + 2 * levels;
    #[cfg(not(embree_instance_array))]
    let hit_arrays = 7 + levels;
    assert_eq!(size_of::<RTCHit8>(), (hit_arrays * 8 * 4).next_multiple_of(32));
    assert_eq!(offset_of!(RTCRayHit8, hit), size_of::<RTCRay8>());
    assert_eq!(offset_of!(RTCRayHit16, hit), size_of::<RTCRay16>());
    assert_eq!(offset_of!(RTCHit8, instID), 7 * 8 * 4);
}

#[repr(C, align(64))]
struct GuardedPacket {
    before: [u32; 16],
    valid: [i32; 8],
    rayhit: RTCRayHit8,
    after: [u32; 64],
}

#[test]
fn instanced_packet_hit_with_a_partial_mask_stays_within_the_packet() {
    // SAFETY: as in the single-ray test; the packet and its mask are 32-byte aligned inside a
    // 64-byte aligned struct (`valid` is at offset 64, `rayhit` at 96).
    unsafe {
        let device = rtcNewDevice(ptr::null());
        let prototype = triangle_scene(device);
        let top = rtcNewScene(device);
        let inst = rtcNewGeometry(device, RTCGeometryType::RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(inst, prototype);
        let xf: [f32; 12] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0];
        rtcSetGeometryTransform(inst, 0, RTCFormat::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xf.as_ptr().cast());
        rtcCommitGeometry(inst);
        rtcAttachGeometryByID(top, inst, 5);
        rtcReleaseGeometry(inst);
        rtcCommitScene(top);

        let mut g = GuardedPacket {
            before: [CANARY; 16],
            valid: [0; 8],
            rayhit: RTCRayHit8::default(),
            after: [CANARY; 64],
        };
        assert_eq!((&g.rayhit as *const RTCRayHit8 as usize) % 32, 0);
        assert_eq!((g.valid.as_ptr() as usize) % 32, 0);
        let (ray, hit) = (&mut g.rayhit.ray, &mut g.rayhit.hit);
        for i in 0..8 {
            // Lanes 0-3 aim at the triangle, 4-7 beside it; odd lanes are inactive.
            g.valid[i] = if i % 2 == 0 { -1 } else { 0 };
            ray.org_x[i] = if i < 4 { 0.25 } else { 5.0 };
            ray.org_y[i] = 0.25;
            ray.dir_z[i] = 1.0;
            ray.tfar[i] = f32::INFINITY;
            ray.mask[i] = u32::MAX;
            hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
            hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect8(g.valid.as_ptr(), top, &mut g.rayhit, ptr::null_mut());
        assert_eq!(rtcGetDeviceError(device), RTCError::RTC_ERROR_NONE);
        assert!(g.before.iter().all(|&c| c == CANARY), "Embree wrote before the packet");
        assert!(g.after.iter().all(|&c| c == CANARY), "Embree wrote past RTCRayHit8");
        let hit = &g.rayhit.hit;
        for i in 0..8 {
            let expect_hit = i % 2 == 0 && i < 4;
            assert_eq!(hit.geomID[i] != RTC_INVALID_GEOMETRY_ID, expect_hit, "lane {i}");
            if expect_hit {
                assert_eq!((hit.instID[0][i], hit.geomID[i], hit.primID[i]), (5, 0, 0));
                assert!((g.rayhit.ray.tfar[i] - 2.0).abs() < 1e-6);
            } else if i % 2 == 1 {
                assert_eq!(g.rayhit.ray.tfar[i], f32::INFINITY, "inactive lane {i} was written");
            }
        }
        rtcReleaseScene(top);
        rtcReleaseScene(prototype);
        rtcReleaseDevice(device);
    }
}
