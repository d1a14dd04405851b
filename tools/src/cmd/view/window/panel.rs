//! The side panel: what the viewer runs on and draws, and the settings a user changes live.

use hce_geometry::lighting::Reconstruction;

use super::content::ObjectStats;
use super::Settings;

/// What the panel shows that it does not change.
pub struct Facts<'a> {
    pub file: Option<&'a str>,
    pub adapter: &'a str,
    pub software: bool,
    pub camera: String,
    pub camera_source: &'a str,
    pub objects: &'a [ObjectStats],
    pub triangles: u64,
    pub frame_ms: f64,
    pub refine_ms: f64,
    /// Level changes left for later frames by the refine budget.
    pub pending: usize,
    pub message: Option<&'a str>,
}

/// What the user asked for with the panel's buttons.
#[derive(Default)]
pub struct Actions {
    pub reset_camera: bool,
    pub screenshot: bool,
    /// The panel's width in points: the scene is drawn to its right.
    pub width: f32,
}

pub fn show(ui: &mut egui::Ui, facts: &Facts<'_>, settings: &mut Settings) -> Actions {
    let mut actions = Actions::default();
    let response = egui::Panel::left("hce view panel")
        .default_size(310.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                ui.heading("hce view");
                ui.label(
                    facts
                        .file
                        .unwrap_or("no file: drop a .glb, .gltf, .hce or .obj here"),
                );
                ui.label(format!("adapter: {}", facts.adapter));
                if facts.software {
                    ui.colored_label(
                        egui::Color32::from_rgb(255, 170, 60),
                        "software rasteriser: no GPU in use",
                    );
                }
                ui.label(format!(
                    "frame {:.1} ms, last refinement {:.1} ms",
                    facts.frame_ms, facts.refine_ms
                ));
                ui.label(format!("{} triangles drawn", facts.triangles));
                if let Some(m) = facts.message {
                    ui.separator();
                    ui.label(m);
                }

                ui.separator();
                ui.strong("Levels");
                let mut auto = settings.levels.forced.is_none();
                ui.horizontal(|ui| {
                    ui.radio_value(&mut auto, true, "from the view");
                    ui.radio_value(&mut auto, false, "forced");
                });
                if auto {
                    settings.levels.forced = None;
                    let lod = &mut settings.levels.lod;
                    ui.add(
                        egui::Slider::new(&mut lod.target_pixels_per_edge, 1.0..=64.0)
                            .logarithmic(true)
                            .text("pixels per edge"),
                    );
                    ui.add(egui::Slider::new(&mut lod.min_level, 0..=6).text("lowest level"));
                    ui.add(egui::Slider::new(&mut lod.max_level, 0..=6).text("highest level"));
                    lod.max_level = lod.max_level.max(lod.min_level);
                } else {
                    let level = settings.levels.forced.get_or_insert(2);
                    ui.add(egui::Slider::new(level, 0..=6).text("level"));
                }

                ui.add(
                    egui::Slider::new(&mut settings.levels.refine_budget_ms, 0.0..=50.0)
                        .text("refine budget (ms per frame)"),
                );
                if facts.pending > 0 {
                    ui.label(format!(
                        "{} level changes left for the next frames",
                        facts.pending
                    ));
                }

                ui.separator();
                ui.strong("Reconstruction");
                ui.horizontal(|ui| {
                    for (r, name) in [
                        (Reconstruction::Smooth, "smooth"),
                        (Reconstruction::NearestNormal, "nearest"),
                        (Reconstruction::Gouraud, "gouraud"),
                    ] {
                        ui.radio_value(&mut settings.reconstruction, r, name);
                    }
                });
                ui.add(
                    egui::Slider::new(&mut settings.exposure, -6.0..=6.0).text("exposure (stops)"),
                );

                ui.separator();
                ui.strong("Camera");
                ui.label(format!("{} (start: {})", facts.camera, facts.camera_source));
                ui.horizontal(|ui| {
                    actions.reset_camera = ui.button("reset (R)").clicked();
                    actions.screenshot = ui.button("screenshot (F12)").clicked();
                });
                egui::CollapsingHeader::new("controls").show(ui, |ui| {
                    ui.label(
                        "left drag: orbit · right drag: look around · middle or shift+left \
                         drag: pan · wheel: towards or away from the pivot\n\
                         W A S D, Q E: fly (shift faster, ctrl slower)\n\
                         0-6: force a level · L: levels from the view · N: next reconstruction\n\
                         Tab: hide the panel · F12 or P: screenshot · R: reset the camera\n\
                         drop a file on the window to open it",
                    );
                });

                ui.separator();
                ui.strong("Objects");
                egui::Grid::new("objects").striped(true).show(ui, |ui| {
                    ui.label("name");
                    ui.label("level");
                    ui.label("triangles");
                    ui.label("refine ms (GPU)");
                    ui.end_row();
                    for o in facts.objects.iter().filter(|o| o.instances > 0) {
                        ui.label(&o.name).on_hover_text(o.kind);
                        ui.label(o.level.to_string());
                        if o.instances == 1 {
                            ui.label(o.triangles.to_string());
                        } else {
                            ui.label(format!("{} x {}", o.triangles, o.instances));
                        }
                        let frames = match o.refine_frames {
                            0 | 1 => String::new(),
                            n => format!(" / {n} frames"),
                        };
                        match o.refine_gpu_ms {
                            Some(g) => ui.label(format!("{:.2} ({g:.2}){frames}", o.refine_ms)),
                            None => ui.label(format!("{:.2}{frames}", o.refine_ms)),
                        }
                        .on_hover_text(
                            "wall time, GPU work waited for (GPU timestamps), over the frames \
                             the refinement was spread over",
                        );
                        ui.end_row();
                    }
                });
            });
        });
    actions.width = response.response.rect.width();
    actions
}
