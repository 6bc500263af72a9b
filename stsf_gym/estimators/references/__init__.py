"""The field's references on the same data: a factor-graph smoother (:mod:`.smoother`), Monte
Carlo localization (:mod:`.mcl`) and each episode's floor (:mod:`.floor`), the offline batch
smoother over all of an episode's measurements: the best any estimator could do with them.

The smoothers share one measurement model (:mod:`.measurements`) and one set of factors
(:mod:`.factors`); Monte Carlo localization weighs its particles by a likelihood field of the
map's walls (:mod:`.likelihood_field`) and by the same landmark detections.
"""
