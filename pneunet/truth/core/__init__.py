"""The truth-finding core shared by both kinds of data: parameter fits with honest
intervals (:mod:`.lsq`, :mod:`.intervals`), the noise floor from the data alone
(:mod:`.noise`), where the residual sits (:mod:`.locate`), the verdict and its error
waterfall (:mod:`.verdict`, :mod:`.waterfall`).  May import: common, physics, engine.
"""
