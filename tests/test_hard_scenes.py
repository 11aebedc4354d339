"""The hard scenes beside the standard sets: a blank wall (Middlebury 2014's Vintage) and
shelves (ETH3D's terrains_2l and terrains_2s). Every local method fails on them; these
ceilings hold today's figures plus a small margin (tests/figures.yaml) so that no change
makes them worse."""

import numpy as np
import pytest

from vsmatch import datasets, evaluation, metrics, pipeline, synthetic

from conftest import standard_scenes
from figures import FIGURES, hold

#: The hard scenes of each data set (bad 2.0 for Middlebury 2014, bad 1.0 for ETH3D, nonocc);
#: their keys in tests/figures.yaml are ``<set>/<config>/<scene>``.
HARD = {"middlebury2014-quarter": ["Vintage"], "eth3d": ["terrains_2l", "terrains_2s"]}

#: The key of each data set in tests/figures.yaml.
KEYS = {"middlebury2014-quarter": "middlebury2014", "eth3d": "eth3d", "kitti2015": "kitti2015",
        "middlebury2": "middlebury2", "middlebury-third": "middlebury-third"}


@pytest.mark.data
@pytest.mark.parametrize("dataset", list(HARD))
def test_default_on_the_hard_scenes(data_dir, dataset):
    scenes = datasets.load_dataset(dataset, data_dir, names=HARD[dataset])
    report = evaluation.evaluate(scenes, {"default": "default"}, dataset=dataset)
    for name in HARD[dataset]:
        hold(f"{KEYS[dataset]}/default/{name}",
             report["methods"]["default"]["scenes"][name]["nonocc"])


@pytest.mark.data
@pytest.mark.parametrize("dataset", list(KEYS))
def test_accurate_gains_on_the_hard_scenes_and_loses_nothing_elsewhere(data_dir, dataset):
    """accurate's figures (its wide-region planes, bridges, refit, long arms,
    vsmatch.surfaces; its depth edges, vsmatch.edges): on the hard scenes a point below
    default's at least, and the mean of each standard set within today's figure."""
    scenes = datasets.load_dataset(dataset, data_dir)
    report = evaluation.evaluate(scenes, {"accurate": "accurate"}, dataset=dataset)
    figures = evaluation.headline_figures(report, "accurate")  # KITTI: all pixels
    for name in HARD.get(dataset, []):
        hold(f"{KEYS[dataset]}/accurate/{name}", figures[name])
        default = FIGURES[f"{KEYS[dataset]}/default/{name}"]["measured"]
        assert figures[name] < default - 1.0, (name, figures[name], default)
    standard = [figures[s.name] for s in standard_scenes(scenes)]
    hold(f"{KEYS[dataset]}/accurate", sum(standard) / len(standard))


#: Changes of the input too small to matter (scripts/perturbed.py): each view given sensor
#: noise of 1 grey level (seeded by the scene's place in its set and the seed), or 3 columns
#: cut. Noise in three seeds: one seed's lead between the configs moved by 0.3 from seed to
#: seed on Middlebury 2014.
SMALL_CHANGES = {
    "noise": [lambda scene, index, seed=seed: evaluation.with_sensor_noise(scene, index, 1.0,
                                                                           seed)
              for seed in (0, 1, 2)],
    "cut": [lambda scene, index: evaluation.without_left_columns(scene, 3)],
}


@pytest.mark.data
@pytest.mark.parametrize("dataset", ["middlebury2014-quarter", "eth3d"])
@pytest.mark.parametrize("change", list(SMALL_CHANGES))
def test_accurate_keeps_its_lead_under_small_changes_of_the_input(data_dir, dataset, change):
    """A step fitted to the scenes as they are loses its gain when they change a little
    (Vintage's wall: 9.95 as it is, 15.4 with 3 columns cut; docs/results.md, "Small
    changes of the input"). On the standard scenes with sensor noise (the mean over three
    seeds) or a cut, each config's mean is held, and accurate's stays below default's."""
    # Each scene's place in the whole set seeds its noise, as in scripts/perturbed.py.
    scenes = [(index, scene) for index, scene in enumerate(datasets.load_dataset(dataset,
                                                                                  data_dir))
              if scene.name not in HARD.get(dataset, [])]
    configs = {"default": "default", "accurate": "accurate"}
    means: dict[str, list[float]] = {name: [] for name in configs}
    for make in SMALL_CHANGES[change]:
        changed = [make(scene, index) for index, scene in scenes]
        report = evaluation.evaluate(changed, configs, dataset=dataset)
        for name in configs:
            means[name].append(float(np.mean(list(
                evaluation.headline_figures(report, name).values()))))
    mean = {name: float(np.mean(values)) for name, values in means.items()}
    for name, value in mean.items():
        hold(f"perturbed/{KEYS[dataset]}/{name}/{change}", value)
    assert mean["accurate"] < mean["default"], means


@pytest.mark.data
def test_accurate_keeps_a_dark_objects_match_in_a_shadow(data_dir):
    """Adirondack's lower left quarter in deep shadow (0.12 of its light, sensor noise 1;
    vsmatch.synthetic.shadowed, as scripts/dark_object.py): the chair's dark body there is
    matched mostly right but reads unsure, and accurate's wide regions spanned it with the
    background's plane (bad 2.0 over the shadow 25.3 against default's 9.6). A shadow's
    pixels keep their own match (surfaces.shadow): about default's figure, held."""
    scene = datasets.load_dataset("middlebury2014-quarter", data_dir, names=["Adirondack"])[0]
    left, right, region = synthetic.shadowed(scene.left, scene.right, scene.ground_truth)
    known = scene.masks["nonocc"] & region
    result = pipeline.run(left, right, max_disp=scene.max_disp, config="accurate")
    hold("dark_object/accurate/Adirondack",
         metrics.bad_percent(result.disparity, scene.ground_truth, known, 2.0))


@pytest.mark.data
def test_accurate_keeps_the_matches_of_a_dark_scene(data_dir):
    """ETH3D's playground_1s darkened all over (gain 0.3, sensor noise 1.5 in each view;
    vsmatch.synthetic.darkened with the seeds scripts/dark_views.py gives it, 12 and 13):
    the matchability gate puts a third of its pixels near confidence 0, most of them right,
    and accurate's surfaces replaced them (bad 1.0 9.99, against default's 3.99). In the dark
    of a dark scene (surfaces.dark_level, dark_share), a pixel whose cost curves show a
    margin keeps its match: held."""
    scene = datasets.load_dataset("eth3d", data_dir, names=["playground_1s"])[0]
    left = synthetic.darkened(scene.left, 0.3, 1.5, 12)
    right = synthetic.darkened(scene.right, 0.3, 1.5, 13)
    result = pipeline.run(left, right, max_disp=scene.max_disp, config="accurate")
    hold("dark_views/accurate/playground_1s",
         metrics.bad_percent(result.disparity, scene.ground_truth, scene.masks["nonocc"], 1.0))
