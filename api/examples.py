"""Worked examples for /docs, from the sources' reference cases (docs/references.md)."""

from fastapi.openapi.models import Example

DRAG_LINK = {
    "ground": 0.1,
    "crank": 0.225,
    "coupler": 0.2504,
    "follower": 0.275,
    "follower_arm": 0.15,
    "connecting_rod": 0.3,
}

# the textbook chapter's Example 3 (a rod longer than the lever)
WHITWORTH = {"crank": 75, "pivot_distance": 50, "lever": 150, "connecting_rod": 200}

ANALYZE = {
    "podhorodeski": Example(
        summary="Podhorodeski et al. (2005): the drag-link project at θ2 = 60°, ω2 = 10 rad/s",
        value={
            "mechanism": {"type": "drag_link_slider", "params": DRAG_LINK},
            "crank_speed": 10.0,
            "crank_angles_deg": [60.0],
        },
    ),
    "lab_rig": Example(
        summary="the slotted-lever lab handout: the lab's crank and slotted lever, every 10°",
        value={
            "mechanism": {
                "type": "crank_shaper",
                "params": {"crank": 40, "pivot_distance": 160, "lever": 240},
            },
            "samples": 36,
        },
    ),
    "textbook": Example(
        summary="the textbook chapter, Example 3: Whitworth (with a rod longer than the lever)",
        value={
            "mechanism": {"type": "whitworth", "params": WHITWORTH},
        },
    ),
    "loads": Example(
        summary="the same Whitworth driving a shaper's ram: a 2 kN cut at 40 strokes a minute",
        value={
            "mechanism": {"type": "whitworth", "params": WHITWORTH},
            "load": {
                "length_unit": "mm",
                "crank_rpm": 40,
                "cutting_force": 2000,
                "slider_mass": 60,
                "link_mass_per_length": 8,
            },
            "samples": 72,
        },
    ),
}

SYNTHESIZE = {
    "podhorodeski": Example(
        summary="Podhorodeski et al. (2005): a new coupler for the drag-link (two solutions)",
        value={
            "time_ratio": 1.5,
            "stroke": 0.3,
            "min_transmission_angle_deg": 0,
            "mechanisms": [
                {
                    "type": "drag_link_slider",
                    "fixed": {
                        "ground": 0.1,
                        "crank": 0.225,
                        "follower": 0.275,
                        "connecting_rod": 0.3,
                    },
                }
            ],
        },
    ),
    "textbook": Example(
        summary="the textbook chapter, Example 2 inverted: TR 2, stroke 450, pivot distance 240",
        value={
            "time_ratio": 2,
            "stroke": 450,
            "mechanisms": [{"type": "crank_shaper", "fixed": {"pivot_distance": 240}}],
        },
    ),
    "every_type": Example(
        summary="Every quick-return type for TR 1.5, stroke 0.3, transmission ≥ 20°",
        value={"time_ratio": 1.5, "stroke": 0.3, "min_transmission_angle_deg": 20},
    ),
}

SWEEP = {
    "drag_link_project_fig5": Example(
        summary="Podhorodeski et al. (2005), Fig. 5: the adjustable coupler's range",
        value={
            "mechanism": {"type": "drag_link_slider", "params": DRAG_LINK},
            "vary": "coupler",
            "start": 0.1,
            "stop": 0.5,
            "points": 101,
        },
    ),
}

EXPORT = {
    "whitworth_dxf": Example(
        summary="The Whitworth drive of the textbook's Example 3, in mm, for CAD",
        value={
            "mechanism": {"type": "whitworth", "params": WHITWORTH},
            "format": "dxf",
            "crank_angle_deg": 30.0,
            "length_unit": "mm",
            "paths": True,
        },
    ),
}

REPORT = {
    "whitworth_loaded": Example(
        summary="The textbook's Whitworth drive against its targets, cutting 2 kN at 40 rpm",
        value={
            "mechanism": {"type": "whitworth", "params": WHITWORTH},
            "targets": {"stroke": 300.0, "bound_deg": 30.0},
            "load": {
                "length_unit": "mm",
                "crank_rpm": 40.0,
                "cutting_force": 2000.0,
                "slider_mass": 20.0,
            },
        },
    ),
}
