"""Object mapping under an uncertain vehicle position: the particle sum-product (SPA) mapper of
paper 003 (:mod:`autonomy.mapping.spa_mapper`), its loopy belief-propagation data
association (:mod:`autonomy.mapping.data_association`) and vehicle motion model
(:mod:`autonomy.mapping.auv_motion`)."""
