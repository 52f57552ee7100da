// SPDX-License-Identifier: GPL-2.0-or-later
/*
 * Appended by build-modules.sh to vimc-core.c in place of its module init and exit, which
 * register one platform device: `n_devs` devices instead (vimc.0, vimc.1, ...), each its own
 * media device, so that libcamera's vimc pipeline handler sees that many cameras.
 */
#define VIMC_MAX_DEVS 8

static unsigned int n_devs = 1;
module_param(n_devs, uint, 0444);
MODULE_PARM_DESC(n_devs, " number of vimc instances (media devices), 1 to 8, default 1");

static struct platform_device vimc_pdevs[VIMC_MAX_DEVS];

static int __init vimc_init(void)
{
	unsigned int i;
	int ret;

	if (n_devs < 1 || n_devs > VIMC_MAX_DEVS) {
		pr_err("vimc: n_devs=%u is not between 1 and %d\n", n_devs, VIMC_MAX_DEVS);
		return -EINVAL;
	}
	ret = platform_driver_register(&vimc_pdrv);
	if (ret)
		return ret;
	for (i = 0; i < n_devs; i++) {
		vimc_pdevs[i].name = VIMC_PDEV_NAME;
		vimc_pdevs[i].id = i;
		vimc_pdevs[i].dev.release = vimc_dev_release;
		ret = platform_device_register(&vimc_pdevs[i]);
		if (ret) {
			pr_err("vimc: device %u registration failed (err=%d)\n", i, ret);
			platform_device_put(&vimc_pdevs[i]);
			while (i-- > 0)
				platform_device_unregister(&vimc_pdevs[i]);
			platform_driver_unregister(&vimc_pdrv);
			return ret;
		}
	}
	return 0;
}

static void __exit vimc_exit(void)
{
	unsigned int i = n_devs;

	while (i-- > 0)
		platform_device_unregister(&vimc_pdevs[i]);
	platform_driver_unregister(&vimc_pdrv);
}

module_init(vimc_init);
module_exit(vimc_exit);

MODULE_DESCRIPTION("Virtual Media Controller Driver (VIMC), several instances");
MODULE_LICENSE("GPL");
