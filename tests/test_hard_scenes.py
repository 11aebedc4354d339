"""The hard scenes beside the standard sets: a blank wall (Middlebury 2014's Vintage) and
shelves (ETH3D's terrains_2l and terrains_2s). Every local method fails on them; these
bounds hold today's figures (measured + a margin) so that no change makes them worse."""

import pytest

from vsmatch import datasets, evaluation

#: default's figure per scene (bad 2.0 for Middlebury 2014, bad 1.0 for ETH3D, nonocc):
#: measured, and the ceiling held.
MEASURED = {"middlebury2014-quarter": {"Vintage": (18.81, 19.5)},
            "eth3d": {"terrains_2l": (17.45, 18.2), "terrains_2s": (21.79, 22.6)}}


@pytest.mark.data
@pytest.mark.parametrize("dataset", list(MEASURED))
def test_default_on_the_hard_scenes(data_dir, dataset):
    scenes = datasets.load_dataset(dataset, data_dir, names=list(MEASURED[dataset]))
    report = evaluation.evaluate(scenes, {"default": "default"}, dataset=dataset)
    for name, (measured, ceiling) in MEASURED[dataset].items():
        figure = report["methods"]["default"]["scenes"][name]["nonocc"]
        assert figure <= ceiling, (name, figure, measured)


#: accurate's figures (its wide-region planes, bridges, refit, long arms, vsmatch.surfaces;
#: its depth edges, vsmatch.edges), measured, and the ceilings held: on the hard scenes, and
#: the mean of each standard set (default's: middlebury2 2.52, middlebury-third 5.79,
#: Middlebury 2014's eight 7.08, ETH3D's nine 3.76, KITTI's D1 6.34). middlebury2's ceiling
#: is the issue's target.
ACCURATE = {"middlebury2014-quarter": ({"Vintage": (9.27, 9.6)}, (6.68, 6.85)),
            "eth3d": ({"terrains_2l": (5.62, 6.1), "terrains_2s": (7.59, 8.1)},
                      (3.08, 3.25)),
            "kitti2015": ({}, (4.64, 4.9)),
            "middlebury2": ({}, (2.32, 2.4)),
            "middlebury-third": ({}, (5.66, 5.79))}


@pytest.mark.data
@pytest.mark.parametrize("dataset", list(ACCURATE))
def test_accurate_gains_on_the_hard_scenes_and_loses_nothing_elsewhere(data_dir, dataset):
    from conftest import standard_scenes

    hard, (measured_mean, ceiling_mean) = ACCURATE[dataset]
    scenes = datasets.load_dataset(dataset, data_dir)
    report = evaluation.evaluate(scenes, {"accurate": "accurate"}, dataset=dataset)
    figures = evaluation.headline_figures(report, "accurate")  # KITTI: all pixels
    for name, (measured, ceiling) in hard.items():
        assert figures[name] <= ceiling, (name, figures[name], measured)
        assert figures[name] < MEASURED[dataset][name][0] - 1.0  # default's, a point less
    standard = [figures[s.name] for s in standard_scenes(scenes)]
    assert sum(standard) / len(standard) <= ceiling_mean, (standard, measured_mean)
